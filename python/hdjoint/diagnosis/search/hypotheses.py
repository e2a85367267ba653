"""A tested hypothesis (an effect's parameters freed, with its held-out
evidence and the acceptance rule read from rules.py) and a finding."""
from __future__ import annotations

import math
from dataclasses import dataclass, field


from hdjoint.diagnosis.fit.priors import Calibrated
from hdjoint.diagnosis import normal as norm

from hdjoint.diagnosis.effects import Effect
from hdjoint.diagnosis.rules import FALSE_DISCOVERY_RATE, MIN_GAIN, SEEN_BIC, UNCONFIRMED_GAIN, steady_over_folds
from hdjoint.diagnosis.model.structure import HeldOutGain, Order


def delta_bic(n_eff: float, mse_before: float, mse_after: float, added: int) -> float:
    """BIC with `added` parameters less BIC without, over n_eff independent training samples."""
    return n_eff * math.log(max(mse_after, 1e-300) / max(mse_before, 1e-300)) + added * math.log(n_eff)




@dataclass
class Hypothesis:
    """One effect tried in one round of the selection: its fit and evidence."""
    effect: Effect
    params_before: dict
    params_after: dict
    fitted: list[str]
    gain: HeldOutGain
    delta_bic: float
    orders: list[Order] = field(default_factory=list)
    # Largest held-out MSE after/before over the effect's channels; for a hypothesis seen on the torsion,
    # the channels' pooled held-out MSE after/before instead (pooled_ratio), as its gain is not theirs.
    worst_channel_ratio: float = 1.0
    pooled_ratio: float | None = None
    degenerate: str | None = None  # why the fit is not the effect it stands for (Effect.degenerate)
    p_raw: float = 1.0
    p_value: float = 1.0  # Benjamini-Hochberg adjusted over the round
    # An effect uneven over the folds by nature: its pooled held-out gain in standard deviations of the null's.
    z_against_null: float | None = None
    # Judged on the encoders' torsion (torsion_orders.py), not on the torque channels: what it was
    # seen on, and its parameters' intervals from that fit (calibration's refit leaves them alone).
    seen_on: str | None = None
    intervals: dict | None = None

    def evidence_z(self) -> float:
        """The z its acceptance and confidence read: over the folds, or against the null (Effect.uneven_over_folds)."""
        return self.gain.z if self.z_against_null is None else self.z_against_null

    def pooled_evidence(self) -> dict:
        """For the record: the z an effect uneven over the folds is judged by (nothing for the others)."""
        return {} if self.z_against_null is None else {"z_against_null": round(self.z_against_null, 2)}

    def confidence(self) -> float:
        """Its confidence before sharing it with look-alikes: how far its held-out
        z (evidence_z) clears 2, times one less its multiplicity-corrected p-value."""
        return float(norm.cdf(self.evidence_z() - 2.0)) * (1.0 - self.p_value)

    def accepted(self) -> bool:
        return self.p_value <= FALSE_DISCOVERY_RATE and self._held_out_evidence()

    def unconfirmed(self) -> bool:
        """Explains most of the held-out residual on every other count, but the
        simulated null cannot tell it from the residual's own colour: a residual
        made of one slow swing (a link channel's gravity the nominal set lacks) makes
        every smooth hypothesis look like noise. Not a finding, not consistent either."""
        return self.p_value > FALSE_DISCOVERY_RATE and self.gain.gain >= UNCONFIRMED_GAIN and self._held_out_evidence()

    def explains_as_much_as(self, other: "Hypothesis") -> bool:
        """Significant, at least `other`'s held-out gain, and every other count of
        acceptance but steadiness over the folds."""
        return (self.p_value <= FALSE_DISCOVERY_RATE and self.gain.gain >= other.gain.gain
                and self._held_out_evidence(steady=False))

    def _held_out_evidence(self, steady: bool = True) -> bool:
        return (not self.degenerate and self.gain.gain > MIN_GAIN and (not steady or self._steady_over_folds())
                and self.delta_bic < SEEN_BIC and self.channel_ratio() <= 1.0)

    def channel_ratio(self) -> float:
        """What the torque channels do held out with it: the worst one's ratio, or their pooled one."""
        return self.worst_channel_ratio if self.pooled_ratio is None else self.pooled_ratio

    def _steady_over_folds(self) -> bool:
        """A stationary effect helps most held-out folds (rules.steady_over_folds). An
        effect uneven over the folds by nature (Effect.uneven_over_folds: a
        drift, a dead zone) is judged by its pooled gain against the
        simulated null, which is its p-value restated, so the p-value alone
        decides (benchmarks/false_alarms.py measures the false alarms this
        gives on controls)."""
        if self.z_against_null is not None:
            return True
        return steady_over_folds(self.gain)


@dataclass
class Finding:
    """An accepted hypothesis ("added"), a look-alike set ("ambiguous"), or a
    calibrated effect beyond its tolerance ("resized")."""
    effect: Effect
    kind: str
    params_before: dict
    params_after: dict
    fitted: list[str]
    p_value: float
    confidence: float
    hypothesis: Hypothesis | None = None      # the test behind an added / ambiguous finding
    alternatives: list[Hypothesis] = field(default_factory=list)  # its look-alikes, for "ambiguous"
    runner_up: Hypothesis | None = None
    resized: list[Calibrated] = field(default_factory=list)
    resize_gain: HeldOutGain | None = None  # what the resize predicts held out (held at its tolerance against not)
    own_evidence: dict | None = None  # evidence the effect adds of its own (Effect.settle), for findings.json

    @property
    def orders(self) -> list[Order]:
        return self.hypothesis.orders if self.hypothesis else []

    def named(self) -> list[str]:
        """The effect and its look-alikes: what this finding names."""
        return [self.effect.id] + [h.effect.id for h in self.alternatives]
