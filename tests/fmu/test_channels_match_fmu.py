"""The diagnosis's motor and link torque channels (hdjoint.diagnosis.model.torque_estimates) are the
joint's own physics: run on the joint's true motion, with every effect of the
motor and link equations on, they give the joint's transmitted torque.

The motor channel once had its own numpy friction without the max(0, .)
clamp of the friction drift: with Fc_drift < 0 and a run longer than
1/|Fc_drift|, it turned the friction around (see test_friction_drift_...)."""
from __future__ import annotations

import numpy as np
import pytest

from hdjoint import _core
from hdjoint.diagnosis.model import torque_estimates as channels
from hdjoint.io import parameters
from hdjoint.io.recording import Recording
from hdjoint.diagnosis.model.kinematics import Kinematics

DT = 1e-4
EFFECTS = {  # every effect of the motor and link equations (LuGre and warm-up replace the drift law: off)
    "Fc": 0.05, "Fs": 0.03, "omega_s": 5.0, "Fc_drift": -0.01, "Bm": 5e-5,
    "cog_a": 0.004, "cog_b": -0.002, "cog_order": 6.0,
    "Fl": 0.4, "Bl": 0.08, "mgl": 5.0,
    "hys_H": 0.3, "backlash": 2e-4, "Df": 2.0,  # the transmission's effects shape tau_joint too
    "max_step": DT,
}



def _simulate(p, duration, dt):
    t = np.arange(0.0, duration, dt)
    i_m = 1.5 * np.sin(2 * np.pi * 0.4 * t) + 0.5 * np.sin(2 * np.pi * 1.7 * t)
    return t, i_m, _core.simulate_joint(parameters.for_plant(p), t, i_m, np.zeros_like(t))


@pytest.fixture(scope="module")
def params():
    return {**parameters.defaults(), **EFFECTS}


def _prepared(t, i_m, out):
    """A recording of the true motion, with exact speeds and central-difference
    accelerations; its "smoothing" is none, and its derivative (the current
    is read as the derivative of its charge) a central difference too."""
    rec = Recording(time=t, i_m=i_m, theta_m=out["theta_m"], theta_l=out["theta_l"], tau_sensor=None,
                    extra={}, path=None)
    omega_m, omega_l = out["omega_m"], out["omega_link"]
    alpha_m, alpha_l = np.gradient(omega_m, DT), np.gradient(omega_l, DT)  # central differences
    kin = Kinematics(omega_m=omega_m, alpha_m=alpha_m, omega_l=omega_l, alpha_l=alpha_l,
                     smooth=lambda x, deriv=0: np.gradient(np.asarray(x, float), t) if deriv else np.asarray(x, float),
                     valid=np.ones(len(t), bool))
    return channels.Prepared(rec, kin, t - t[0])


def test_friction_drift_is_the_joints_clamped_law_on_a_long_run(params):
    # 105 s: past t = 1/|Fc_drift| = 100 s, where 1 + Fc_drift*t turns negative.
    motor_only = {**params, "hys_H": 0.0, "backlash": 0.0, "Df": 0.0, "max_step": 1e-3}
    t, _, out = _simulate(motor_only, 105.0, 1e-2)
    friction = channels.motor_friction(params, out["omega_m"], t)
    # The same C++ function; the joint's clock sums its steps, so t differs by round-off.
    np.testing.assert_allclose(friction, out["tau_friction"], rtol=0, atol=1e-12)
    late = t > 101.0
    assert np.all(out["friction_scale"][late] == 0.0)  # the clamp is what these rows test
    assert np.max(np.abs(out["tau_friction"][late])) > 0.0
    # The old numpy copy, 1 + Fc_drift*t unclamped, reversed the Coulomb friction
    # here: by up to 0.0027 N.m at 105 s, N times that (0.27 N.m) in tau_M.
    p = params
    unclamped = ((1.0 + p["Fc_drift"] * t) * (p["Fc"] + p["Fs"] * np.exp(-(out["omega_m"] / p["omega_s"]) ** 2))
                 * np.tanh(out["omega_m"] / p["omega_fc"]) + p["Bm"] * out["omega_m"])
    assert np.max(np.abs(unclamped - out["tau_friction"])[late]) > 0.0025


def test_motor_and_link_channels_give_the_joints_torque(params):
    t, i_m, out = _simulate(params, 3.0, DT)
    prep = _prepared(t, i_m, out)
    rows = np.flatnonzero(prep.kin.valid)[int(0.5 / DT):]  # after the start-up transient
    tau = out["tau_joint"][rows]
    assert np.ptp(tau) > 2.0
    # Central-difference accelerations leave a residual of order N*Jm*d(alpha)
    # and Jl*d(alpha) (largest where the friction switches at zero speed), far
    # below the effects' (N*Fc = 5 N.m, N*cogging = 0.45 N.m, Fl = 0.4 N.m).
    motor_error = np.abs(channels.tau_motor(prep, params)[rows] - tau)
    link_error = np.abs(channels.tau_link(prep, params)[rows] - tau)
    assert np.median(motor_error) < 0.005 and np.percentile(motor_error, 99) < 0.02, motor_error
    assert np.median(link_error) < 5e-4 and np.percentile(link_error, 99) < 0.01, link_error
