"""Stribeck friction, or a Coulomb law of another shape near zero speed?

Both put friction near zero speed that the nominal tanh law lacks. A
Stribeck rise is a steady law: the extra friction stays while the speed is
held in its range (0.5-20 rad/s). A sharper smoothing of the Coulomb law, or
a bristle model (LuGre: the bristles' damping acts while they deflect),
changes friction only while the speed passes through zero: at a speed held
away from it the friction is Fc again. Yet on a recording whose speed is
never held, a Stribeck fit explains such a joint's residual as well.

The C++ friction law has no bristle state, so that look-alike is not fitted
on its own. It is judged on the Stribeck fit's own structure: Stribeck is
told apart from it only by its held-out gain where the speed is held
(`held_speed`). Without that evidence the two are one ambiguous finding,
each with the share of the held-out gain it can claim. (A fit with omega_s
below omega_fc never gets here: it is degenerate, `StribeckFriction.degenerate`.)"""
from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from hdjoint.diagnosis.effects.base import Effect, RecordingScale, Size, TruthDraw
from hdjoint.diagnosis.effects.coulomb_friction import EFFECT as COULOMB
from hdjoint.diagnosis.model.kinematics import Kinematics
from hdjoint.diagnosis.rules import EVIDENCE_Z
from hdjoint.diagnosis.model.structure import fold_z, relative_fold_gains

# The speed range a Stribeck rise is tested over (the effect's `revealed_by`).
STRIBECK_SPEEDS = (0.5, 20.0)  # rad/s
# A sample is at a held speed when the speed would change by less than
# HELD_CHANGE of itself over HELD_FOR, and the last reversal is at least
# HELD_FOR ago (a 3 Hz swing through zero is never held).
HELD_FOR = 0.1  # s
HELD_CHANGE = 0.2
MIN_HELD_SAMPLES = 20  # per held-out fold that counts
MIN_HELD_FOLDS = 4


@dataclass
class SteadyEvidence:
    """The Stribeck fit's held-out gain at held speeds, and its share of the whole."""
    held_share: float      # share of the held-out samples at held speeds
    gain: float            # held-out gain there (nan: too few held folds)
    z: float               # over the held-out folds that have held speeds
    folds: int
    steady_share: float    # share of the hypothesis's held-out improvement made at held speeds

    @property
    def separates(self) -> bool:
        return bool(np.isfinite(self.z) and self.z > EVIDENCE_Z and self.gain > 0.0)


def held_speed(kin: Kinematics, time: np.ndarray) -> np.ndarray:
    """Samples whose motor speed is held in the Stribeck range: in range, not
    changing by more than HELD_CHANGE of itself within HELD_FOR, and HELD_FOR
    past the last reversal."""
    speed = np.abs(kin.omega_m)
    lo, hi = STRIBECK_SPEEDS
    steady = (speed >= lo) & (speed <= hi) & (np.abs(kin.alpha_m) * HELD_FOR < HELD_CHANGE * speed)
    sign = np.sign(kin.omega_m)
    flips = np.flatnonzero(np.diff(sign) != 0) + 1
    since = np.full(len(time), np.inf)
    if len(flips):
        last = np.searchsorted(flips, np.arange(len(time)), side="right") - 1
        has = last >= 0
        since[has] = time[has] - time[flips[last[has]]]
    return steady & (since >= HELD_FOR)


def steady_evidence(before: np.ndarray, after: np.ndarray, held: np.ndarray, fold: np.ndarray,
                    test: np.ndarray) -> SteadyEvidence:
    """The hypothesis's held-out gain (per-sample squared residuals `before`
    and `after`) on the held-out samples at held speeds, fold by fold."""
    rows = test & held & np.isfinite(before) & np.isfinite(after)
    improvement = np.nansum((before - after)[test])
    steady_share = float(np.sum((before - after)[rows]) / improvement) if improvement > 0 else 0.0
    share = float(np.count_nonzero(rows) / max(np.count_nonzero(test), 1))
    means = [(np.mean(before[here]), np.mean(after[here])) for here in (rows & (fold == f) for f in np.unique(fold[rows]))
             if np.count_nonzero(here) >= MIN_HELD_SAMPLES]
    relative = relative_fold_gains(*np.array(means).reshape(-1, 2).T)
    relative = relative[np.isfinite(relative)]
    if len(relative) < MIN_HELD_FOLDS:
        return SteadyEvidence(share, float("nan"), float("nan"), len(relative), steady_share)
    gain = 1.0 - float(np.mean(after[rows]) / max(np.mean(before[rows]), 1e-300))
    return SteadyEvidence(share, gain, fold_z(relative), len(relative), min(max(steady_share, 0.0), 1.0))


# The look-alike, as an entry of the effect library's kind (it names the
# Coulomb law the nominal model already has, mis-shaped near zero speed).
# Not a candidate of the library: it is never fitted on its own.
SMOOTHING_LOOKALIKE = Effect(
    "coulomb_friction", "motor", (),
    "Coulomb friction of another shape near zero speed: a sharper smoothing than omega_fc allows, or bristles "
    "(LuGre) whose damping acts while the speed passes through zero",
    "not in the C++ law (a sharper tanh or a bristle state): judged on the Stribeck fit's structure",
    lookalikes=("stribeck_friction",),
    revealed_by="the same held slow speeds: friction back at Fc once the speed is held (no Stribeck rise)")


class StribeckFriction(Effect):
    def degenerate(self, p: dict, scale: RecordingScale) -> str | None:
        """A Stribeck rise narrower than the Coulomb law's own smoothing is no
        rise: the law is (Fc + Fs*exp(-(w/omega_s)^2))*tanh(w/omega_fc), so with
        omega_s below omega_fc the extra level lives only where tanh is still
        switching, and beyond omega_fc friction is Fc again. What it fits is the
        shape of the switch through zero speed, a Coulomb law of another shape
        (a sharper or two-stage switch, LuGre's bristles)."""
        if p["omega_s"] >= p["omega_fc"]:
            return None
        return (f"the fitted rise (omega_s = {p['omega_s']:.2g} rad/s) lies inside the Coulomb law's own switch "
                f"(omega_fc = {p['omega_fc']:.2g} rad/s): it reshapes friction while the speed passes through zero, "
                f"a Coulomb law of another shape, not friction above Fc at low speed")

    def settle(self, finding, objective):
        """Where the nominal set has Coulomb friction, an accepted Stribeck rise
        or a Coulomb law of another shape near zero speed: told apart only by
        its held-out gain at held slow speeds; otherwise one ambiguous finding."""
        if not COULOMB.is_on(objective.nominal):
            return finding
        h = finding.hypothesis
        channels = objective.channels_of(h.effect.part)
        held = held_speed(objective.prep.kin, objective.rec.time)
        steady = steady_evidence(objective.squared(h.params_before, channels), objective.squared(h.params_after, channels),
                                 held, objective.fold, objective.test)
        finding.own_evidence = {"at_held_slow_speeds": {
            "share_of_held_out_samples": round(steady.held_share, 3), "held_out_gain": _finite(steady.gain, 4),
            "z": _finite(steady.z, 2), "folds": steady.folds, "share_of_the_gain": round(steady.steady_share, 3),
            "tells_apart_from_smoothing": steady.separates}}
        objective.say(f"stribeck_friction at held slow speeds: gain {steady.gain:.3g} (z = {steady.z:.2g}, "
                   f"{steady.folds} folds, {100 * steady.held_share:.0f} % of the held-out samples)")
        if steady.separates:
            return finding
        lookalike = replace(h, effect=SMOOTHING_LOOKALIKE, params_after=h.params_before, fitted=[],
                            gain=replace(h.gain, gain=h.gain.gain * (1.0 - steady.steady_share)), orders=[])
        alternatives = [a for a in finding.alternatives if a.effect.id != SMOOTHING_LOOKALIKE.id] + [lookalike]
        share = h.gain.gain / (h.gain.gain + sum(max(a.gain.gain, 0.0) for a in alternatives))
        confidence = h.confidence() * share
        return replace(finding, kind="ambiguous", alternatives=alternatives, confidence=round(confidence, 3))

    def plant_in_truth(self, draw: TruthDraw) -> None:
        draw.truth.update(Fs=0.01 * draw.scaled(), omega_s=8.0 * draw.jitter())


def _finite(x: float, digits: int):
    return round(float(x), digits) if np.isfinite(x) else None


EFFECT = StribeckFriction(
    "stribeck_friction", "motor", ("Fs", "omega_s"),
    "Stribeck friction: higher friction at low speed", "(Fc + Fs*exp(-(omega/omega_s)^2))*tanh(...)",
    switched_by=("Fs",), starts=({"Fs": 0.005, "omega_s": 3.0}, {"Fs": 0.01, "omega_s": 15.0},
                                 {"Fs": 0.02, "omega_s": 50.0}),
    needs=("low_speed",), lookalikes=("coulomb_friction",),
    revealed_by="slow constant speeds (0.5-20 rad/s) held in both directions, not only passed through",
    resizes=("Fs", "omega_s"), in_friction_law=True, size=Size("Fs", reference=(("Fs", 0.01),)), rank=2)
