"""The resize stage: effects the nominal model has, with a calibrated
parameter beyond its tolerance, and needed there. Held at the edge of its
tolerance (the rest refitted), the model must predict held-out data
significantly worse; a parameter that only wandered along a look-alike's
direction (bl1 against a0 and Kf on a short link travel) costs nothing held
out and is not a finding."""
from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from hdjoint.diagnosis import normal as norm
from hdjoint.diagnosis.fit.priors import Calibrated, Prior
from hdjoint.diagnosis.effects import EFFECTS, Effect, owner
from hdjoint.diagnosis.search.hypotheses import Finding
from hdjoint.diagnosis.fit.objective import Objective
from hdjoint.diagnosis.model.prepare import unresolved_harmonics
from hdjoint.diagnosis.rules import (EVIDENCE_Z, FALSE_DISCOVERY_RATE, GROSS_CHECKED, GROSS_FACTOR, GROSS_RATIO,
                                     HYPOTHESIS_FTOL, INTERVAL_Z, MIN_GAIN, RESIZE_Z)
from hdjoint.diagnosis.search.selection import Selection
from hdjoint.diagnosis.model.structure import held_out_gain_sq
from hdjoint.io import parameters


def resized(objective: Objective, selection: Selection, calibration: dict[str, Calibrated],
            settled: set[str] = frozenset()) -> tuple[list[Finding], list[dict]]:
    """The resized findings at the selection's set, and as unexplained
    structure the needed moves of harmonics the recording's travel does not
    resolve (unresolved_harmonics). The held fit starts at the edge of the
    band (RESIZE_Z tolerances). Parameters `settled` (by `released`) are not tested again."""
    p = selection.params
    moved: dict[tuple[str, bool], list[Calibrated]] = {}
    unresolved = unresolved_harmonics(objective.rec, p)
    for c in calibration.values():
        effect = owner(c.name)
        if effect is not None and c.beyond_tolerance and c.name not in settled:
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


@dataclass(frozen=True)
class Released:
    """What the released priors found: resized findings (a parameter an
    effect owns), unexplained entries with their size (a constant of the
    joint no effect owns, e.g. Jl), and the selection with the corrected set
    carrying the estimates (the same selection when nothing was found)."""
    findings: list[Finding]
    unexplained: list[dict]
    selection: Selection


def released(objective: Objective, selection: Selection, calibration: dict[str, Calibrated]) -> Released:
    """Parameters of GROSS_CHECKED a nominal set may have off by a factor:
    refitted with their prior GROSS_FACTOR times the nominal value wide.
    One that lands beyond RESIZE_Z tolerances there, within GROSS_FACTOR
    times its nominal value either way, (or already did in the
    calibration, where the prior may have held it short) is tested as `resized` tests:
    held at the edge of its tolerance, the rest refitted, the model must
    predict held-out data worse (compared at the noise as measured). One
    within RESIZE_Z tolerances but off by GROSS_RATIO either way is needed
    when its released interval excludes that factor. A
    needed one is a resized finding of its owner with the released
    estimate and interval, or, owned by none, unexplained structure with
    its size in N.m; the corrected set takes the released estimate. It runs
    before `resized`, which then leaves these parameters alone."""
    p = selection.params
    names = [n for n in GROSS_CHECKED if n in calibration]
    if not names:
        return Released([], [], selection)
    free = list(dict.fromkeys(objective.calibrated_names + selection.added_names))
    wide = {n: Prior(objective.priors[n].centre, GROSS_FACTOR * max(abs(objective.priors[n].centre),
                                                                    objective.priors[n].std)) for n in names}
    objective.say(f"refitting {', '.join(names)} with their priors {GROSS_FACTOR:g} times their nominal value wide")
    # Judged to HYPOTHESIS_FTOL, as hypotheses are: a released parameter far
    # off wanders for many steps before a 1e-8 change of the cost, each step
    # a finite-difference Jacobian over every calibrated parameter.
    jointly = objective.with_priors(wide).fit(p, free, objective.channels, ftol=HYPOTHESIS_FTOL)
    candidates = []
    for n in names:
        c = calibration[n]
        moved = abs(jointly.params[n] - c.prior.centre) > RESIZE_Z * c.prior.std
        if c.beyond_tolerance or moved or _ratio_edge(jointly.params[n], c.prior.centre) is not None:
            candidates.append(n)
    findings, unexplained = [], []
    for n in candidates:
        prior = objective.priors[n]
        # Its interval is read at the optimum: this fit converges as the calibration's does (stopped at
        # HYPOTHESIS_FTOL, a stiffness far off sat short of it with half its deviation).
        unheld = objective.with_priors({n: wide[n]}).fit(dict(p, **{n: jointly.params[n]}), free, objective.channels)
        estimate, std = unheld.params[n], unheld.std.get(n, prior.std)
        beyond_tolerance = abs(estimate - prior.centre) > RESIZE_Z * prior.std
        ratio_edge = _ratio_edge(estimate, prior.centre)
        if not beyond_tolerance and ratio_edge is None:
            continue
        if not _within_factor(estimate, prior.centre):
            objective.say(f"{n}: released to {estimate:.4g} (nominal {prior.centre:.4g}), beyond {GROSS_FACTOR:g} "
                          "times either way: another part, not this one mis-sized (degenerate)")
            continue
        edge = (prior.centre + math.copysign(RESIZE_Z * prior.std, estimate - prior.centre) if beyond_tolerance
                else ratio_edge)
        held = objective.fit(dict(p, **{n: edge}), [m for m in free if m != n], objective.channels, ftol=HYPOTHESIS_FTOL)
        gain = held_out_gain_sq(objective.at_measured_noise(held.params), objective.at_measured_noise(unheld.params),
                                objective.fold, objective.test)
        level = FALSE_DISCOVERY_RATE / len(candidates)
        # Its released interval lies wholly beyond the edge of its stated tolerance band (or of the factor):
        # needed by its interval, even where holding it there costs little held out (a stiff joint's
        # torsion near the encoders' resolution says little of the stiffness, yet excludes the nominal).
        band = prior.centre + math.copysign(prior.std, estimate - prior.centre) if beyond_tolerance else edge
        p_interval = float(norm.sf(abs(estimate - band) / max(std, 1e-300)))
        by_interval = p_interval <= level and abs(estimate - band) > INTERVAL_Z * std
        if beyond_tolerance:
            p_gain = float(norm.sf(gain.z))
            by_gain = gain.gain > MIN_GAIN and p_gain <= level and gain.z > EVIDENCE_Z
            needed, p_value = by_gain or by_interval, (p_gain if by_gain else p_interval)
        else:  # within tolerances but off by a factor: its released interval must exclude that factor
            needed, p_value = by_interval, p_interval
        objective.say(f"{n}: released to {estimate:.4g} [{estimate - INTERVAL_Z * std:.4g}, "
                      f"{estimate + INTERVAL_Z * std:.4g}] (nominal {prior.centre:.4g}); held at {edge:.4g}, "
                      f"held-out gain {100 * gain.gain:.2f} % (z = {gain.z:.1f}), p = {p_value:.2g}")
        if not needed:
            continue
        moved = Calibrated(n, objective.nominal.get(n, prior.centre), estimate,
                           unheld.std.get(n, prior.std), prior)
        effect = owner(n)
        if effect is not None:
            findings.append(_resize_or_lookalike(selection, Finding(
                effect, "resized", held.params, unheld.params, [n], p_value,
                round(float(norm.cdf(norm.isf(max(p_value, 1e-300)) - 2.0)), 3), resized=[moved], resize_gain=gain)))
        else:
            unexplained += _constant_off(objective, moved, p, unheld.params, gain, p_value)
        p = unheld.params
        selection = replace(selection, params=p, last_fit=unheld)
    return Released(findings, unexplained, selection)


def _ratio_edge(estimate: float, nominal: float) -> float | None:
    """GROSS_RATIO times (or over) the nominal value on the estimate's side,
    when the estimate lies beyond it with the same sign; else None."""
    if nominal == 0.0 or estimate / nominal <= 0.0:
        return None
    ratio = abs(estimate / nominal)
    if ratio > GROSS_RATIO:
        return nominal * GROSS_RATIO
    return nominal / GROSS_RATIO if ratio < 1.0 / GROSS_RATIO else None


def _within_factor(estimate: float, nominal: float) -> bool:
    """|estimate| within GROSS_FACTOR times |nominal| either way (a sign may
    flip: where mgl's zero lies is a convention). A stiffness released to
    1/5000 of the catalogue's zeroed the transmission's torque on LARA8
    joint1_jog and explained 38 % held out by saying nothing."""
    if nominal == 0.0:
        return True
    ratio = abs(estimate / nominal)
    return 1.0 / GROSS_FACTOR <= ratio <= GROSS_FACTOR


def _constant_off(objective: Objective, c: Calibrated, before: dict, after: dict, gain, p_value: float) -> list[dict]:
    """A constant of the joint no effect owns, off by a factor: unexplained
    structure on the channel it changes most, with the torque it misses."""
    from hdjoint.diagnosis.verdict.floors import torque_span
    lo, hi = c.interval
    unit = parameters.table()[c.name].unit
    span = torque_span(objective, after)
    sizes = {}
    for ch in objective.channels:
        d = (objective.shown_residual(ch, dict(after, **{c.name: c.nominal})) - objective.shown_residual(ch, after))
        d = d[objective.test & np.isfinite(d)]
        sizes[ch.name] = float(np.sqrt(np.mean(d * d))) if len(d) else 0.0
    channel = max(sizes, key=sizes.get)
    ratio = c.nominal / c.estimate if c.estimate else float("inf")
    return [{"channel": channel,
             "feature": (f"{c.name}: the nominal {c.nominal:.4g} {unit} is {ratio:.2g} times what the recording says, "
                         f"{c.estimate:.4g} [{lo:.4g}, {hi:.4g}] {unit} (z {c.z:.1f}); held to its tolerance's edge, "
                         f"{100 * gain.gain:.0f} % worse held out. No effect of the library owns it: the corrected "
                         "set carries the estimate"),
             "size_Nm": round(sizes[channel], 6), "share_of_span": round(sizes[channel] / span, 6) if span > 0 else None,
             "parameter": c.name, "nominal": c.nominal, "estimate": c.estimate, "interval": [lo, hi],
             "held_out_gain": round(gain.gain, 4), "z": round(gain.z, 1), "p_value": p_value, "largest_at": "-"}]
