"""The detection limits read the last round's simulated null when it was
made at the corrected set (Diagnosis.null_noise_at): the limits are the
same as with a null made anew, and that null is not made twice."""
import numpy as np
import pytest

from hdjoint.diagnosis.detection_limit import detection_limits
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint_truth.cases import CONTROL_CASES, draw, record

pytestmark = pytest.mark.slow


def test_limits_on_the_rounds_own_null_equal_those_on_a_fresh_one():
    joint = draw(next(c for c in CONTROL_CASES if c.name == "control on multisine"), 1, duration=12.0)
    result, doc = diagnose(record(joint, 0), joint.nominal)
    assert doc["verdict"] == "consistent" and doc["detection_limits"]
    diag, p = result.engine, result.params
    assert diag.null_noise_at(p) is diag._noise  # the last round accepted nothing: made at this very set
    assert diag.null_noise_at(dict(p)) is not diag._noise  # an equal set made elsewhere: made anew
    fresh = diag._null_noise(p)
    assert np.array_equal(fresh.replicates([0]), diag._noise.replicates([0]))
    diag._noise = None  # as before: every limit made its own
    again = [x.as_dict() for x in detection_limits(diag, p)]
    assert again == doc["detection_limits"]
