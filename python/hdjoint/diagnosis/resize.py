"""The resize stage: effects the nominal model has, with a calibrated
parameter beyond its tolerance, and needed there. Held at the edge of its
tolerance (the rest refitted), the model must predict held-out data
significantly worse; a parameter that only wandered along a look-alike's
direction (bl1 against a0 and Kf on a short link travel) costs nothing held
out and is not a finding."""
from __future__ import annotations

import math
from dataclasses import replace

from scipy.stats import norm

from hdjoint.diagnosis.calibration import Calibrated
from hdjoint.diagnosis.effects import EFFECTS, Effect, owner
from hdjoint.diagnosis.hypotheses import Finding
from hdjoint.diagnosis.objective import Objective
from hdjoint.diagnosis.prepare import unresolved_harmonics
from hdjoint.diagnosis.rules import EVIDENCE_Z, FALSE_DISCOVERY_RATE, MIN_GAIN, RESIZE_Z
from hdjoint.diagnosis.select import Selection
from hdjoint.diagnosis.structure import held_out_gain_sq


def resized(objective: Objective, selection: Selection,
            calibration: dict[str, Calibrated]) -> tuple[list[Finding], list[dict]]:
    """The resized findings at the selection's set, and as unexplained
    structure the needed moves of harmonics the recording's travel does not
    resolve (unresolved_harmonics). The held fit starts at the edge of the
    band (RESIZE_Z tolerances)."""
    p = selection.params
    moved: dict[tuple[str, bool], list[Calibrated]] = {}
    unresolved = unresolved_harmonics(objective.rec, p)
    for c in calibration.values():
        effect = owner(c.name)
        if effect is not None and c.beyond_tolerance:
            moved.setdefault((effect.id, c.name in unresolved), []).append(c)
    out, unattributed = [], []
    for (effect_id, is_unresolved), params in moved.items():
        edge = {c.name: c.prior.centre + math.copysign(RESIZE_Z * c.prior.std, c.z) for c in params}
        free = [n for n in objective.calibrated_names + selection.added_names if n not in edge]
        # Both fits from the same start and by the same steps: only the held parameters differ.
        held = objective.fit(dict(p, **edge), free, objective.channels)
        unheld = objective.fit(p, free + list(edge), objective.channels)
        gain = held_out_gain_sq(objective.squared(held.params, objective.channels),
                                objective.squared(unheld.params, objective.channels), objective.fold, objective.test)
        p_value = float(norm.sf(gain.z))
        objective.say(f"{effect_id}: {', '.join(edge)} beyond tolerance; held to it, held-out gain "
                      f"{100 * gain.gain:.2f} % (z = {gain.z:.1f})")
        if not (gain.gain > MIN_GAIN and p_value <= FALSE_DISCOVERY_RATE / max(1, len(moved)) and gain.z > EVIDENCE_Z):
            continue
        if is_unresolved:
            unattributed += _unattributed_move(objective, EFFECTS[effect_id], params, unresolved, gain, p_value)
            continue
        out.append(_resize_or_lookalike(selection, Finding(
            EFFECTS[effect_id], "resized", held.params, p, [c.name for c in params], p_value,
            round(float(norm.cdf(gain.z - 2.0)), 3), resized=params, resize_gain=gain)))
    return sorted(out, key=lambda f: f.p_value), unattributed


def _unattributed_move(objective: Objective, effect: Effect, params: list[Calibrated], unresolved: dict[str, str],
                       gain, p_value: float) -> list[dict]:
    """A needed move of harmonics the travel does not resolve: structure
    the model needs, not a resized `effect` (a confident name it cannot back)."""
    moves = ", ".join(f"{c.name} {c.nominal:.2g} -> {c.estimate:.2g}" for c in params)
    why = "; and ".join(dict.fromkeys(unresolved[c.name] for c in params))  # both angles' terms may have moved
    feature = (f"what {moves} take up beyond tolerance (held to it, {100 * gain.gain:.0f} % worse held out), "
               f"but {why}: {effect.id} is one candidate, not a finding")
    return [{"channel": c.name, "feature": feature, "held_out_gain": round(gain.gain, 4),
             "z": round(gain.z, 1), "p_value": p_value, "largest_at": "-"}
            for c in objective.channels_of(effect.part)]


def _resize_or_lookalike(selection: Selection, finding: Finding) -> Finding:
    """A resized finding, or an ambiguous one when a look-alike the model
    lacks, tested in the last round, explains at least as much held-out
    structure of the same part as the resize does. The resize is fitted
    first (calibration), so it takes what it can of the look-alike's
    structure, which may then fall short of acceptance on its own."""
    effect = finding.effect
    rivals = [h for h in selection.last_round
              if h.effect.part == effect.part and not h.degenerate
              and effect.looks_like(h.effect)
              and h.gain.gain >= finding.resize_gain.gain]
    if not rivals:
        return finding
    share = finding.resize_gain.gain / (finding.resize_gain.gain + sum(h.gain.gain for h in rivals))
    return replace(finding, kind="ambiguous", alternatives=rivals, confidence=round(finding.confidence * share, 3))
