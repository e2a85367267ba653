"""A resized finding is reported as one of a look-alike set when a look-alike
the model lacks explains at least as much held-out structure of the same
part (resize._resize_or_lookalike): calibration fits the resize first,
so it takes what it can of the look-alike's structure (backlash s0 of the
independent truth: `Cw` resized at 11.6 % held out, the backlash hypothesis
18 % on top of it in too few folds to be accepted)."""
from types import SimpleNamespace

import numpy as np

from hdjoint.diagnosis.fit.priors import Calibrated, Prior
from hdjoint.diagnosis.verdict.resize import _resize_or_lookalike
from hdjoint.diagnosis.search.hypotheses import Finding, Hypothesis
from hdjoint.diagnosis.effects import EFFECTS
from hdjoint.diagnosis.model.structure import HeldOutGain


def _gain(g, z=2.0):
    return HeldOutGain(g, z, np.full(20, g))


def _hypothesis(effect, gain, degenerate=None):
    return Hypothesis(EFFECTS[effect], {}, {effect: 1.0}, [], _gain(gain), -100.0, degenerate=degenerate)


def _resized(gain):
    cw = Calibrated("Cw", 10.0, 120.0, 5.0, Prior(10.0, 5.0))
    return Finding(EFFECTS["wave_generator_compliance"], "resized", {}, {"Cw": 120.0}, ["Cw"], 7e-4, 0.88,
                   resized=[cw], resize_gain=_gain(gain, 3.2))


def _decide(finding, last_round):
    return _resize_or_lookalike(SimpleNamespace(last_round=last_round), finding)


def test_a_lookalike_that_explains_more_makes_the_resize_one_of_two():
    f = _decide(_resized(0.1155), [_hypothesis("backlash", 0.1818), _hypothesis("time_delay", 0.5)])
    assert f.kind == "ambiguous" and [a.effect.id for a in f.alternatives] == ["backlash"]  # not another part's
    assert f.confidence == round(0.88 * 0.1155 / (0.1155 + 0.1818), 3)


def test_a_lookalike_that_explains_less_or_is_degenerate_leaves_the_resize_alone():
    assert _decide(_resized(0.1155), [_hypothesis("backlash", 0.05)]).kind == "resized"
    degenerate = _hypothesis("backlash", 0.3, degenerate="a dead zone wider than the torsion")
    assert _decide(_resized(0.1155), [degenerate]).kind == "resized"
    assert _decide(_resized(0.1155), []).kind == "resized"
