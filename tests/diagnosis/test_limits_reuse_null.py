"""The detection limits read the last round's simulated null when it was
made at the corrected set (HypothesisSearch.null_noise_at): the limits are the
same as with a null made anew, and that null is not made twice."""
import numpy as np
import pytest

from hdjoint.diagnosis.verdict.detection_limit import detection_limits
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.diagnosis.search.significance import null_noise
from hdjoint_truth.cases import CONTROL_CASES, draw, record

pytestmark = pytest.mark.slow


def test_limits_on_the_rounds_own_null_equal_those_on_a_fresh_one():
    joint = draw(next(c for c in CONTROL_CASES if c.name == "control on multisine"), 1, duration=12.0)
    result, doc = diagnose(record(joint, 0), joint.nominal)
    assert doc["verdict"] == "consistent" and doc["detection_limits"]
    search, p = result.search, result.params
    assert search.null_noise_at(p) is search.noise  # the last round accepted nothing: made at this very set
    assert search.null_noise_at(dict(p)) is not search.noise  # an equal set made elsewhere: made anew
    fresh = null_noise(result.objective, p)
    assert np.array_equal(fresh.replicates([0]), search.noise.replicates([0]))
    search.noise = None  # as before: every limit made its own
    again = [x.as_dict() for x in detection_limits(search, result.selection)]
    assert again == doc["detection_limits"]
