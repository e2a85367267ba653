"""Deciding among a round's accepted hypotheses: the best one by held-out
gain is a finding; a look-alike that explains as much, and cannot be told
apart fold by fold, makes it ambiguous."""
from __future__ import annotations

from hdjoint.diagnosis.search.hypotheses import Finding, Hypothesis
from hdjoint.diagnosis.rules import SEPARATED_RATIO, SEPARATED_Z
from hdjoint.diagnosis.model.structure import fold_z


def separated(best: Hypothesis, rival: Hypothesis) -> bool:
    """The better hypothesis explains clearly more held-out structure than the rival, fold by fold."""
    clearly = fold_z(best.gain.fold_gains - rival.gain.fold_gains) > SEPARATED_Z
    return bool(clearly and rival.gain.gain <= SEPARATED_RATIO * best.gain.gain)


def rival(best: Hypothesis, other: Hypothesis) -> bool:
    """A look-alike of the best that explains the same structure, not clearly
    less of it: accepted on its own, or explaining at least as much held out
    and significant against the simulated null, though uneven over the folds.
    Naming the best alone would then be a confident name the data do not
    single out: a look-alike can explain as much as the best while being
    too uneven over the folds to be accepted on its own."""
    if not best.effect.looks_like(other.effect):
        return False
    return (other.accepted() or other.explains_as_much_as(best)) and not separated(best, other)


def finding_for(best: Hypothesis, others: list[Hypothesis]) -> Finding:
    """An added finding, or an ambiguous one when a look-alike explains the same
    structure and is significant on its own."""
    rivals = [o for o in others if rival(best, o)]
    runner_up = others[0] if others else None
    confidence = best.confidence()
    if not rivals:
        return Finding(best.effect, "added", best.params_before, best.params_after, best.fitted, best.p_value,
                       round(confidence, 3), best, runner_up=runner_up)
    share = best.gain.gain / (best.gain.gain + sum(r.gain.gain for r in rivals))
    return Finding(best.effect, "ambiguous", best.params_before, best.params_after, best.fitted, best.p_value,
                   round(confidence * share, 3), best, alternatives=rivals, runner_up=runner_up)
