"""The selection stage: forward selection over the effects the recording can
test. Each round tries every candidate (search.py), corrects their p-values
over the round (Benjamini-Hochberg), and accepts the best by held-out gain
when the rules accept it (hypotheses.py, rules.py), as one finding or with
a look-alike as an ambiguous one (decide.py); the model is refitted with it
and the next round tries the rest, until none is accepted."""
from __future__ import annotations

from dataclasses import dataclass

from hdjoint.diagnosis.fit.nominal_calibration import Calibration
from hdjoint.diagnosis.search.decide import finding_for
from hdjoint.diagnosis.effects import Effect
from hdjoint.diagnosis.forked import Deferred
from hdjoint.diagnosis.fit.objective import Fit
from hdjoint.diagnosis.search.hypotheses import Finding, Hypothesis
from hdjoint.diagnosis.search.hypothesis_search import HypothesisSearch
from hdjoint.diagnosis.search.significance import benjamini_hochberg


@dataclass(frozen=True)
class Selection:
    params: dict                      # the corrected set
    findings: list[Finding]           # added (and ambiguous) findings, in the order accepted
    last_fit: Fit                     # the fit that gave `params` (calibration's when nothing was accepted)
    added_names: list[str]            # parameters of accepted findings, refitted with calibration's
    tested: list[list[dict]]          # every hypothesis tried, per round (evidence for the report)
    last_round: list[Hypothesis]      # the hypotheses of the round that ended the selection
    last_candidates: list[Effect]     # that round's effects, those without a hypothesis too (no order found)
    unconfirmed: list[Hypothesis]     # large held-out structure the simulated null cannot confirm
    not_testable: list[dict]
    orders_not_found: list[dict]


def _record(h: Hypothesis) -> dict:
    return {"effect": h.effect.id, "held_out_gain": round(h.gain.gain, 5),
            "z": round(h.gain.z, 2), "p_value": h.p_value, "delta_bic": round(h.delta_bic, 1),
            "folds_improved": f"{h.gain.folds_improved}/{h.gain.folds_compared}",
            **({"pooled_channel_ratio": round(h.pooled_ratio, 4)} if h.seen_on else
               {"worst_channel_ratio": round(h.worst_channel_ratio, 4)}),
            "accepted": h.accepted(), **({"degenerate": h.degenerate} if h.degenerate else {}),
            **({"seen_on": h.seen_on, "orders": [{"angle": o.angle, "order": o.order}
                                                 for o in h.orders]} if h.seen_on else {}),
            **h.pooled_evidence()}


def _accept(best: Hypothesis, others: list[Hypothesis], objective, added_names: list[str]):
    """The finding for an accepted hypothesis and the joint refit with it, or
    None when that refit is not physical: calibration and the accepted terms
    settle together, and may carry the new term somewhere its own fit was
    refused from (a warm-up turned into a step). Such a finding is a
    catch-all; the hypothesis is marked degenerate and the next one is tried."""
    finding = finding_for(best, others)
    finding = best.effect.settle(finding, objective)  # the effect's own special case, if any
    # Terms seen on the encoders' torsion stay as fitted there: the torque channels are blind to them.
    refitted = [] if best.seen_on else finding.fitted
    names = objective.calibrated_names + added_names + refitted
    refit = objective.fit(best.params_after, list(dict.fromkeys(names)), objective.channels)
    reason = best.effect.degenerate(refit.params, objective.recording_scale(refit.params))
    if reason is not None:
        best.degenerate = f"refitted with the joint's calibration, {reason}"
        objective.say(f"{best.effect.id} refused: {best.degenerate}")
        return None
    finding.params_after = refit.params
    objective.say(f"found {finding.effect.id} ({finding.kind}): held-out gain {100 * best.gain.gain:.1f} %, "
                  f"p = {best.p_value:.2g}")
    return finding, refit, refitted


def select(search: HypothesisSearch, calibration: Calibration, beside: Deferred | None = None) -> Selection:
    """`beside`: computed with the first round's hypotheses (forked.Deferred)."""
    objective = search.objective
    p, last_fit = calibration.params, calibration.fit
    candidates = search.testable_effects(p)
    findings: list[Finding] = []
    added_names: list[str] = []
    tested: list[list[dict]] = []
    last_round: list[Hypothesis] = []
    last_candidates: list[Effect] = []
    unconfirmed: list[Hypothesis] = []
    while candidates:
        objective.say(f"testing {len(candidates)} hypotheses ({', '.join(e.id for e in candidates)})")
        search.start_round(p)
        tried = search.try_all(candidates, p, beside)
        last_candidates = list(candidates)
        for h, adjusted in zip(tried, benjamini_hochberg([h.p_raw for h in tried])):
            h.p_value = adjusted
        tried.sort(key=lambda h: -h.gain.gain)
        last_round = tried
        accepted = [h for h in tried if h.accepted()]
        # The first accepted hypothesis whose joint refit is physical (_accept marks the others degenerate).
        chosen = next(((h, made) for h in accepted
                       if (made := _accept(h, [o for o in tried if o is not h], objective, added_names))), None)
        tested.append([_record(h) for h in tried])
        if chosen is None:
            unconfirmed = [h for h in tried if h.unconfirmed()]
            break
        best, (finding, refit, refitted) = chosen
        findings.append(finding)
        added_names = list(dict.fromkeys(added_names + refitted))
        last_fit = refit
        p = refit.params
        lookalike_ids = {a.effect.id for a in finding.alternatives}
        candidates = [e for e in candidates if e is not best.effect and e.id not in lookalike_ids]
    return Selection(p, findings, last_fit, added_names, tested, last_round, last_candidates, unconfirmed,
                     list(search.not_testable), list(search.orders_not_found))


def unconfirmed_structure(selection: Selection, objective) -> list[dict]:
    """The unconfirmed hypotheses of the last round, as unexplained structure in their channels."""
    return [{"channel": c.name, "feature": f"what {h.effect.id} would explain (the simulated null cannot "
                                           f"confirm it: p = {h.p_value:.2g}; record longer or a wider motion)",
             "held_out_gain": round(h.gain.gain, 4), "z": round(h.gain.z, 1), "p_value": h.p_value,
             "largest_at": "-"} for h in selection.unconfirmed for c in objective.channels_of(h.effect.part)]
