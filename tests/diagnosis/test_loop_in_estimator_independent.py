"""A fitted Dahl loop as the estimator FMU runs it. Against a sensor the
diagnosis fits the loop on the torsion through the transmission's filter;
the FMU drives it with each raw encoder increment. On the independent
truth's hysteresis case (seed 0) the fitted loop switches over 4.8e-6 rad,
under one encoder count of torsion, and driven raw it makes the held-out
torque error worse: the finding says so, and the report's summary carries
the caveat (docs/diagnosis_measurements.md, "The fitted loop in the estimator FMU")."""
import pytest

from hdjoint.diagnosis import diagnose
from hdjoint.report import build
from hdjoint.truth.cases import EFFECT_CASES, draw, record

pytestmark = pytest.mark.slow


def test_a_loop_the_estimator_cannot_follow_is_said_to_be_so():
    joint = draw(next(c for c in EFFECT_CASES if c.name == "hysteresis"), 0)
    rec = record(joint, 0)
    result, doc = diagnose(rec, joint.nominal)
    loop = next(f for f in doc["findings"] if f["effect"] == "hysteresis")
    raw = loop["in_the_estimator"]
    assert raw["held_out_rms_with"] > raw["held_out_rms_without"] and raw["change"] > 0
    assert "each encoder count flips it" in raw["caveat"]
    assert "Caveat: the estimator FMU" in build(result, doc)
