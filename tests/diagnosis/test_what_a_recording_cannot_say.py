"""Effects a recording's excitation cannot tell from a look-alike are said
to be not testable there (effects.testable), rather than named. Both rules
come from wrong names on the independent truth's controls without a torque
sensor (benchmarks/sensorless_controls.py, seeds 4-7):
  - a dead zone around zero load on constant-speed runs whose load never
    leaves one side of zero (backlash added on seeds 4 and 7);
  - a drift over the run on chirps, where time is frequency (thermal_drift
    added on seeds 4 and 5: LuGre friction, whose bristles change the
    friction with frequency, against the model's static law)."""
from dataclasses import replace

import numpy as np
import pytest

from hdjoint.diagnosis import effects
from hdjoint.diagnosis.fit.objective import Objective
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint.diagnosis.effects import EFFECTS
from hdjoint.diagnosis.effects.needs import FREQUENCY_FOLLOWS_TIME, frequency_time_correlation
from hdjoint_truth.cases import CONTROL_CASES, draw, record

pytestmark = pytest.mark.slow  # each draws and simulates the truth's recordings


def _prepared(case: str, seed: int, sensor: bool):
    joint = draw(next(c for c in CONTROL_CASES if c.name == case), seed, 30.0)
    rec = record(joint, 0) if sensor else replace(record(joint, 0), tau_sensor=None)
    diag = Objective(prepare(rec, joint.nominal, workers=1))
    return diag, diag.reference_torque(diag.initial_offset(joint.nominal))


@pytest.mark.parametrize("sensor", [True, False])
def test_a_dead_zone_is_not_tested_where_the_load_stays_on_one_side_of_zero(sensor):
    diag, torque = _prepared("control on constant_speeds", 7, sensor)
    assert np.nanpercentile(torque, 2) > 0.0  # the situation: gravity holds the load above zero
    assert "one side of zero" in effects.testable(EFFECTS["backlash"], diag.prep, torque)
    # The same load turned negative in every other 5 s passes through zero: testable.
    flipped = np.where((np.arange(len(torque)) // 5000) % 2 == 0, torque, -torque)
    assert effects.testable(EFFECTS["backlash"], diag.prep, flipped) is None
    diag, torque = _prepared("control on sweep", 0, sensor)
    assert effects.testable(EFFECTS["backlash"], diag.prep, torque) is None


def test_a_drift_is_not_tested_on_a_chirp():
    diag, torque = _prepared("control on chirp", 5, False)
    rho = frequency_time_correlation(diag.prep.kin, diag.rec.time)
    assert rho > FREQUENCY_FOLLOWS_TIME
    assert "rises or falls steadily" in effects.testable(EFFECTS["thermal_drift"], diag.prep, torque)
    # The same recording played backwards in time is as confounded.
    kin = replace(diag.prep.kin, omega_m=diag.prep.kin.omega_m[::-1], alpha_m=diag.prep.kin.alpha_m[::-1])
    assert frequency_time_correlation(kin, diag.rec.time) < -FREQUENCY_FOLLOWS_TIME
    for case in ("control on paper", "control on multisine", "control on sweep", "control on constant_speeds"):
        diag, torque = _prepared(case, 0, True)
        assert abs(frequency_time_correlation(diag.prep.kin, diag.rec.time)) < 0.6, case
        assert effects.testable(EFFECTS["thermal_drift"], diag.prep, torque) is None, case
