"""A fitted Dahl loop as the estimator FMU runs it. Against a sensor the
diagnosis fits the loop on the torsion through the transmission's filter;
the FMU drives it with the raw encoder angles. On the independent truth's
hysteresis cases the fitted loops switch over less than one encoder count
of torsion, so the FMU may gain from the loop held out or lose. Each
finding says which, and the report's summary carries the caveat where the
FMU loses."""
import pytest

from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.diagnosis.output.report import build
from hdjoint_truth.cases import EFFECT_CASES, draw, record

pytestmark = pytest.mark.slow


def _loop(seed):
    joint = draw(next(c for c in EFFECT_CASES if c.name == "hysteresis"), seed)
    result, doc = diagnose(record(joint, 0), joint.nominal)
    return result, doc, next(f for f in doc["findings"] if f["effect"] == "hysteresis")


def test_a_loop_the_estimator_loses_by_is_said_to_be_so():
    result, doc, loop = _loop(1)
    raw = loop["in_the_estimator"]
    assert raw["held_out_rms_with"] > raw["held_out_rms_without"] and raw["change"] > 0
    assert "which the FMU does not apply" in raw["caveat"]
    assert "Caveat: the estimator FMU" in build(result, doc)


def test_a_loop_the_estimator_gains_from_has_no_caveat():
    result, doc, loop = _loop(0)
    raw = loop["in_the_estimator"]
    assert raw["held_out_rms_with"] < raw["held_out_rms_without"] and "caveat" not in raw
    assert "Caveat:" not in build(result, doc)
