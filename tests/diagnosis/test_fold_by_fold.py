"""A hypothesis must beat the model of the effects already accepted fold by
fold (issue 38, goal 5): search.try_effect measures its held-out error
against the corrected set of the round (the accepted effects refitted) on
every held-out fold, and rules.steady_over_folds asks that the improvement
stand out of the folds' scatter and reach most folds. A gain pooled from a
few folds is not a finding, however large."""
import numpy as np

from hdjoint.diagnosis.effects import EFFECTS
from hdjoint.diagnosis.search.hypotheses import Hypothesis
from hdjoint.diagnosis.rules import MIN_GAIN, STEADY_FOLD_SHARE
from hdjoint.diagnosis.model.structure import held_out_gain_sq

FOLDS, PER_FOLD = 40, 50
fold = np.repeat(np.arange(FOLDS), PER_FOLD)
test = fold % 2 == 1


def hypothesis(after_per_fold: dict[int, float]) -> Hypothesis:
    """A stationary effect's hypothesis whose held-out squared error, against
    the accepted model's 1.0 everywhere, is `after_per_fold` (1.0 elsewhere);
    every other count of acceptance (p-value, BIC, channels) passes."""
    before = np.ones(len(fold))
    after = np.array([after_per_fold.get(int(f), 1.0) for f in fold])
    gain = held_out_gain_sq(before, after, fold, test)
    h = Hypothesis(EFFECTS["coulomb_friction"], {}, {}, ["Fc"], gain, -100.0, p_raw=1e-6, p_value=1e-6)
    assert not EFFECTS["coulomb_friction"].uneven_over_folds
    return h


def test_a_gain_carried_by_one_fold_is_not_a_finding():
    h = hypothesis({1: 0.0, **{f: 1.02 for f in range(3, FOLDS, 2)}})  # one held-out fold explained, the rest worse
    assert h.gain.gain > MIN_GAIN  # pooled, it would pass
    assert h.gain.folds_improved == 1
    assert not h.accepted()


def test_a_gain_in_too_few_folds_is_not_a_finding_however_steady():
    improved = list(range(1, FOLDS, 2))[: int(0.6 * FOLDS / 2)]  # 60 % of the held-out folds, by 10 % each
    h = hypothesis({f: 0.9 + 0.001 * i for i, f in enumerate(improved)})
    assert h.gain.z > 3.0 and h.gain.gain > MIN_GAIN
    assert h.gain.folds_improved < STEADY_FOLD_SHARE * h.gain.folds_compared
    assert not h.accepted()


def test_the_same_gain_in_every_fold_is_a_finding():
    h = hypothesis({f: 0.97 + 0.001 * (f % 7) for f in range(1, FOLDS, 2)})
    assert h.gain.folds_improved == h.gain.folds_compared == FOLDS // 2
    assert h.accepted()
