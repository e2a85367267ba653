"""The current sensor's errors in the joint-state filter. It learns the gain error (jsf_current_gain): a
sensor that reads 2 % high otherwise biases tau_hat by 2 % of the motor torque, through the compliance
error e. The offset no state can see: its stated accuracy (jsf_current_offset) widens the deviations."""
from __future__ import annotations

import numpy as np
import pytest

from hdjoint import _core
from hdjoint.fmu import experiments
from hdjoint.io import parameters

GAIN_ERROR = 0.02  # a Hall sensor's datasheet class


@pytest.fixture(scope="module")
def run():
    """20 s of the paper's experiment with payload steps; the estimator has the joint's exact model."""
    joint = {**parameters.defaults(), "wg_load": 1.0}  # the plant's wave generator is loaded by the torque
    rec = experiments.run("paper", joint=joint, nominal=joint, duration=20.0, sensors=experiments.Sensors(seed=3),
                          tau_ext=experiments.payload_steps)
    return rec, joint


def _estimate(run, gain_error: float, prior: float, offset: float = 0.0, stated_offset: float = 0.0) -> dict:
    rec, joint = run
    est = _core.run_estimator(parameters.for_estimator({**joint, "jsf_current_gain": prior,
                                                        "jsf_current_offset": stated_offset}), rec.time,
                              (1.0 + gain_error) * rec.i_m + offset, rec.theta_m, rec.theta_l, smooth=True)
    error = {n: est[n] - rec.extra["tau_joint"] for n in ("tau_hat", "tau_smooth")}
    figures = {n: float(np.sqrt(np.mean(e ** 2))) for n, e in error.items()}
    figures["coverage"] = float(np.mean(np.abs(error["tau_hat"]) <= 2.0 * est["tau_hat_std"]))
    figures["smooth coverage"] = float(np.mean(np.abs(error["tau_smooth"]) <= 2.0 * est["tau_smooth_std"]))
    return figures


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_a_sensor_gain_error_costs_tau_hat_nothing_once_learned(run, sign):
    exact = _estimate(run, 0.0, 0.0)
    unknown = _estimate(run, sign * GAIN_ERROR, 0.0)
    learned = _estimate(run, sign * GAIN_ERROR, GAIN_ERROR)
    # Measured: tau_hat 0.030 N.m with an exact sensor, 0.040 with the error unknown, 0.030 learned.
    assert unknown["tau_hat"] > 1.2 * exact["tau_hat"]
    assert learned["tau_hat"] < 1.05 * exact["tau_hat"]
    assert learned["tau_smooth"] < 1.05 * exact["tau_smooth"]
    assert learned["coverage"] > 0.93 > unknown["coverage"]


def test_a_gain_prior_on_an_exact_sensor_costs_nothing(run):
    exact, prior = _estimate(run, 0.0, 0.0), _estimate(run, 0.0, GAIN_ERROR)
    assert prior["tau_hat"] < 1.02 * exact["tau_hat"]
    assert prior["tau_smooth"] < 1.02 * exact["tau_smooth"]


OFFSET_BOUND = 0.01  # A, a datasheet's offset; its std as a uniform draw within it is bound/sqrt(3)


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_an_offset_stays_within_the_deviations_its_stated_accuracy_gives(run, sign):
    std = OFFSET_BOUND / np.sqrt(3.0)
    typical, worst = (_estimate(run, 0.0, 0.0, sign * size, std) for size in (std, OFFSET_BOUND))
    unstated = _estimate(run, 0.0, 0.0, sign * OFFSET_BOUND, 0.0)
    # Measured: the offset biases tau_hat by N*Kt*offset (0.044 N.m at the bound); unstated, +-2 sigma covers
    # 79 % of tau_hat and 50 % of tau_smooth; stated, 92 and 89 % at the bound. The estimate is the same either way.
    assert unstated["coverage"] < 0.85 and unstated["smooth coverage"] < 0.6
    assert typical["coverage"] >= 0.93 and typical["smooth coverage"] >= 0.93
    assert worst["coverage"] >= 0.88 and worst["smooth coverage"] >= 0.85
    assert worst["tau_hat"] == pytest.approx(unstated["tau_hat"], rel=1e-12)
