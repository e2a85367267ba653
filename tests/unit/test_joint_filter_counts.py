"""The joint-state filter reads each encoder count as the interval it bounds
(interval_reading in joint_state_filter.h): with fine encoders the dynamics
predict the angle far inside a count, and only a count's edge tells them
something; the white q^2/12 reading blurred it. On short benchmark-like runs
(default encoders, payload steps, the link model a few percent off, the
benchmark's tuned noise settings) tau_hat and tau_smooth lie further below
the compliance model's error than the white reading let them (about 64 % and
75 % there)."""
import numpy as np
import pytest

from hdjoint import _core
from hdjoint.estimation.metrics import error_figures
from hdjoint.fmu import experiments
from hdjoint.io import parameters

TUNED = {"jsf_q_load": 0.001, "jsf_q_load_rate": 1.0, "jsf_q_motor": 0.0, "jsf_q_torque": 1e-4}


@pytest.mark.parametrize("experiment, seed", [("paper", 11), ("multisine", 5)])
def test_fine_counts_read_as_intervals_beat_the_white_reading(experiment, seed):
    joint = parameters.defaults()
    rec = experiments.run(experiment, joint=joint, nominal=joint, duration=5.0,
                          sensors=experiments.Sensors(seed=seed), tau_ext=experiments.payload_steps)
    p = {**joint, **TUNED, "wg_load": 1.0, "Jl": 1.05 * joint["Jl"], "mgl": 0.96 * joint["mgl"]}
    est = _core.run_estimator(parameters.for_estimator(p), rec.time, rec.i_m, rec.theta_m, rec.theta_l, smooth=True)
    truth = rec.extra["tau_joint"]
    base = error_figures(est["tau_compliance"], truth)
    assert error_figures(est["tau_hat"], truth).reduction_against(base) > 66.5
    assert error_figures(est["tau_smooth"], truth).reduction_against(base) > 76.5
    # Still honest: the truth within +-2 sigma about 95 % of the time.
    for name in ("tau_hat", "tau_smooth"):
        assert 0.93 <= np.mean(np.abs(est[name] - truth) <= 2.0 * est[f"{name}_std"]) <= 0.99
