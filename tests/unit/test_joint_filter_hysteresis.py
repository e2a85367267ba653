"""The joint-state filter on a joint with transmission hysteresis that its
parameters describe (hys_H, hys_sigma, as the diagnosis writes them): the
filter runs the Dahl law on its own torsion, with the loop's slope in its
dynamics. A loop narrower than a motor-encoder count is invisible in the
readings the compliance model follows, and without its slope the filter
misses the stiffening and its +-2 sigma covered well under 95 %."""
from __future__ import annotations

import numpy as np
import pytest

from hdjoint import _core
from hdjoint.estimation.metrics import error_figures
from hdjoint.fmu import experiments
from hdjoint.io import parameters

# Saturates at 0.1 N.m within 3e-6 rad, a fifth of a motor count (link side).
HYSTERESIS = {"hys_H": 0.1, "hys_sigma": 3e4}


@pytest.fixture(scope="module")
def run():
    rec = experiments.run("chirp", joint={**parameters.defaults(), **HYSTERESIS}, nominal=parameters.defaults(),
                          duration=4.0, sensors=experiments.Sensors(seed=5), tau_ext=experiments.contact_pushes)
    p = parameters.for_estimator({**parameters.defaults(), **HYSTERESIS, "wg_load": 1.0})
    return rec.extra["tau_joint"], _core.run_estimator(p, rec.time, rec.i_m, rec.theta_m, rec.theta_l, smooth=True)


def test_filter_deviation_covers_the_hysteretic_torque(run):
    truth, est = run
    coverage = 100.0 * np.mean(np.abs(est["tau_hat"] - truth) <= 2.0 * est["tau_hat_std"])
    assert 90.0 <= coverage <= 99.0, coverage


def test_filter_and_smoother_beat_the_compliance_model(run):
    truth, est = run
    rms = {n: error_figures(est[n], truth).rms for n in ("tau_compliance", "tau_hat", "tau_smooth")}
    assert rms["tau_hat"] < 0.6 * rms["tau_compliance"], rms
    assert rms["tau_smooth"] <= rms["tau_hat"], rms
