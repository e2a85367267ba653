"""A ripple beside another missing effect's broadband residual, on the
independent truth: cogging (order 8) and a 2.8 ms current-sensor lag
concealed together (seed 2's sweep). The lag's residual raises the order's
off-orders (prominence under 3), but the order alone explains most of the
held-out motor residual, so the order search keeps it (structure.DOMINANT_GAIN)
and cogging's own test accepts it."""
import pytest
from threadpoolctl import threadpool_limits

from hdjoint.diagnosis.fit.nominal_calibration import calibrate
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint.diagnosis.search.hypothesis_search import HypothesisSearch
from hdjoint.diagnosis.effects import EFFECTS
from hdjoint_truth.cases import EFFECT_CASES, draw, record

pytestmark = pytest.mark.slow


def test_cogging_under_a_lags_broadband_residual_is_found_and_accepted():
    case = next(c for c in EFFECT_CASES if c.present == ("cogging", "time_delay"))
    joint = draw(case, 2, 30.0)
    assert joint.setups[0].current_sensor.lag > 2e-3 and joint.truth["cog_order"] == 8.0
    with threadpool_limits(limits=1, user_api="blas"):
        calibrated = calibrate(prepare(record(joint, 0), joint.nominal, workers=1))
        p, search = calibrated.params, HypothesisSearch(calibrated.objective, calibrated.current_alignment)
        found = search.order_search(p, "motor", search.objective.channels_of("motor"), ("theta_m",)).found
        assert [o.order for o in found][:1] == [8.0]
        assert found[0].prominence < 3.0 and found[0].gain.gain > 0.3  # kept by its share, not its prominence
        h = search.test_alone(EFFECTS["cogging"], p)
    assert h is not None and h.accepted() and h.params_after["cog_order"] == 8.0
