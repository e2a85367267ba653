"""What a recording cannot tell, said beside a `consistent` verdict.

`consistent` claims that nothing is missing, yet a missing effect can
come out `consistent`: its hypothesis is supported by the training data
but not fold by fold (folds at rest and folds in motion disagree), or
calibration took it into a constant of the joint. The recording could not
tell, and says so:

  - a hypothesis of the last round that was not accepted but explains at
    least SEEN_GAIN of the held-out residual with the training data's
    support (delta BIC < SEEN_BIC);
  - a calibrated constant of the joint (a parameter no effect owns: Kt, Jm,
    Jl, ...) more than ABSORBED_Z tolerances from its nominal value.

  - an effect that would not show at a sourced reference size
    (detection_limit.py: the smallest size this recording shows).

Each item names what to record to settle it (the effect's `revealed_by`).
The verdict is not changed (benchmarks/false_alarms.py measures the
false-alarm rate on the verdict); findings.json carries the list as `cannot_tell` and the
report's summary shows it."""
from __future__ import annotations

from hdjoint.diagnosis.effects import EFFECTS, owner
from hdjoint.diagnosis.rules import ABSORBED_Z, SEEN_BIC, SEEN_GAIN
from hdjoint.io.parameters import meaning



def unsettled_hypotheses(last_round: list[dict], unexplained: list[dict]) -> list[dict]:
    """Hypotheses the recording supports on the whole but not fold by fold."""
    said = {u["feature"] for u in unexplained}
    out = []
    for h in last_round:
        if h["accepted"] or h["held_out_gain"] < SEEN_GAIN or h["delta_bic"] >= SEEN_BIC:
            continue
        if any(h["effect"] in feature for feature in said):
            continue  # already unexplained structure (an unconfirmed hypothesis)
        out.append({"effect": h["effect"],
                    "why": f"explains {100 * h['held_out_gain']:.1f} % of the held-out residual (delta BIC "
                           f"{h['delta_bic']:.0f}), but {_not_enough(h)}",
                    "record": EFFECTS[h["effect"]].revealed_by if h["effect"] in EFFECTS else ""})
    return out


def _not_enough(h: dict) -> str:
    """Why the evidence fell short: the fit is not the effect, the folds (a
    stationary effect), or the simulated null (Effect.uneven_over_folds)."""
    if "degenerate" in h:
        return f"its fit is not the effect: {h['degenerate']}"
    if "z_against_null" in h:
        return (f"no more than noise with the residual's own colour would (z = {h['z_against_null']:.2g} against the "
                f"simulated null, p = {h['p_value']:.2g})")
    return f"not fold by fold (z = {h['z']:.2g}, p = {h['p_value']:.2g})"


def absorbed_constants(calibration: dict) -> list[dict]:
    """Constants of the joint the calibration moved far beyond their tolerance."""
    out = []
    for name, c in calibration.items():
        if owner(name) is not None or abs(c.z) <= ABSORBED_Z or not c.nominal:
            continue
        out.append({"parameter": name,
                    "why": f"calibration moved the {meaning(name)} {name} to {c.estimate / c.nominal:.2f}x its nominal value "
                           f"(z = {c.z:.1f} tolerances): it takes up what this recording cannot name",
                    "record": "another excitation (see the effects' `revealed_by`), or check the nominal value"})
    return out


def too_small_to_show(limits, said: set[str]) -> list[dict]:
    """Effects this recording would not show at a sourced reference size (detection_limit.py)."""
    return [{"effect": x.effect, "why": f"one as large as the reference would not show: {x.sentence()}",
             "record": EFFECTS[x.effect].revealed_by} for x in limits if x.hides_reference() and x.effect not in said]


def cannot_tell(result) -> list[dict]:
    last_round = result.tested[-1] if result.tested else []
    seen = unsettled_hypotheses(last_round, result.unexplained)
    return (seen + too_small_to_show(result.limits, {x["effect"] for x in seen}) +
            absorbed_constants(result.calibration))
