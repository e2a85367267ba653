"""The estimator FMU (through fmpy) and the batch path agree with the
independent numpy oracle in reference_model.py on a simulated recording."""
from __future__ import annotations

import numpy as np
import pytest

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.fmu.runner import run_estimator_fmu

from reference_model import compliance, paper_ukf

OUTPUTS = ("tau_ukf", "tau_compliance", "omega_m", "dtheta_f", "tau_ukf_std")
TOL_TORQUE = 1e-9   # N.m
TOL_TORSION = 1e-13  # rad (1e-9 N.m at Kf = 1e4 N.m/rad)
TOL_SPEED = 1e-9    # rad/s


def max_abs_diff(a, b):
    a, b = np.asarray(a, float), np.asarray(b, float)
    assert a.shape == b.shape
    assert np.isfinite(a).all() and np.isfinite(b).all()
    return float(np.max(np.abs(a - b)))


@pytest.fixture(scope="module")
def fmu_estimates(recording, estimator_params):
    r = recording
    return run_estimator_fmu(r.time, r.i_m, r.theta_m, r.theta_l, estimator_params)


@pytest.fixture(scope="module")
def oracle(recording, estimator_params):
    r = recording
    return paper_ukf(estimator_params, r.i_m, r.theta_m, r.theta_l)


def test_recording_is_not_trivial(recording):
    # The comparison means something only when torque, speed and angles move.
    assert len(recording) == 3001
    assert np.ptp(recording.tau_sensor) > 0.3
    assert np.ptp(np.diff(recording.theta_m)) > 0
    assert np.ptp(recording.i_m) > 0.1


def test_compliance_outputs_equal_oracle(recording, estimator_params, fmu_estimates):
    r = recording
    dtheta_f, tau = compliance(estimator_params, r.i_m, r.theta_m, r.theta_l)
    assert max_abs_diff(fmu_estimates["tau_compliance"], tau) <= TOL_TORQUE
    assert max_abs_diff(fmu_estimates["dtheta_f"], dtheta_f) <= TOL_TORSION
    # And the compliance torque is a real signal, not zeros on both sides.
    assert np.ptp(tau) > 0.3


def test_ukf_outputs_equal_oracle(fmu_estimates, oracle):
    assert max_abs_diff(fmu_estimates["tau_ukf"], oracle["tau_ukf"]) <= TOL_TORQUE
    assert max_abs_diff(fmu_estimates["tau_ukf_std"], oracle["tau_ukf_std"]) <= TOL_TORQUE
    assert max_abs_diff(fmu_estimates["omega_m"], oracle["omega_m"]) <= TOL_SPEED
    assert np.ptp(oracle["tau_ukf"]) > 0.3
    assert np.ptp(oracle["omega_m"]) > 1.0
    # The std settles from ukf_p0_tau = 1 to a steady value well below it.
    assert oracle["tau_ukf_std"][0] < 1.0 and oracle["tau_ukf_std"][-1] < 0.2


def test_batch_path_equals_fmu(recording, estimator_params, fmu_estimates, oracle):
    r = recording
    batch = _core.run_estimator(estimator_params, r.time, r.i_m, r.theta_m, r.theta_l)
    for name in OUTPUTS:
        assert max_abs_diff(batch[name], fmu_estimates[name]) <= 1e-12, name
    assert (np.asarray(batch["status"]) == 0).all()
    # nis is not an FMU output; check it against the oracle instead.
    np.testing.assert_allclose(batch["nis"], oracle["nis"], rtol=1e-6, atol=1e-9)


def test_batch_compliance_equals_oracle(recording, estimator_params):
    r = recording
    dtheta_f, tau = compliance(estimator_params, r.i_m, r.theta_m, r.theta_l)
    got = _core.compliance(estimator_params, r.i_m, r.theta_m, r.theta_l)
    assert max_abs_diff(got["tau_compliance"], tau) <= TOL_TORQUE
    assert max_abs_diff(got["dtheta_f"], dtheta_f) <= TOL_TORSION


@pytest.mark.parametrize("changes", [
    pytest.param({"Cf": 0.0, "Cw": 0.0}, id="linear-laws"),
    pytest.param({"ukf_alpha": 0.5, "ukf_kappa": 0.0, "ukf_beta": 1.0, "ukf_q_tau": 0.1, "ukf_r_omega": 2.0},
                 id="other-ukf-settings"),
    pytest.param({"Kt": 0.05, "Jm": 3e-5, "Kf": 1.2e4, "a0": 1e-5, "omega_l": 3.0, "omega_w": 1.0,
                  "Fc": 0.0, "Bm": 1e-4}, id="other-joint"),
])
def test_fmu_equals_oracle_with_other_parameters(recording, default_params, changes):
    r = recording.slice(0, 1000)
    p = parameters.for_estimator({**default_params, **changes})
    got = run_estimator_fmu(r.time, r.i_m, r.theta_m, r.theta_l, p)
    ref = paper_ukf(p, r.i_m, r.theta_m, r.theta_l)
    assert max_abs_diff(got["tau_compliance"], ref["tau_compliance"]) <= TOL_TORQUE
    assert max_abs_diff(got["dtheta_f"], ref["dtheta_f"]) <= TOL_TORSION
    assert max_abs_diff(got["tau_ukf"], ref["tau_ukf"]) <= TOL_TORQUE
    assert max_abs_diff(got["tau_ukf_std"], ref["tau_ukf_std"]) <= TOL_TORQUE
    assert max_abs_diff(got["omega_m"], ref["omega_m"]) <= TOL_SPEED
    # The parameters reached the FMU: the defaults give a different answer.
    base = paper_ukf(parameters.for_estimator(default_params), r.i_m, r.theta_m, r.theta_l)
    assert max_abs_diff(base["tau_ukf"], ref["tau_ukf"]) > 1e-6


def test_fmu_equals_oracle_with_late_start_time(recording, estimator_params):
    """A recording that starts at t = 1234.5 s: one sample per row still (floating-point time grid)."""
    r = recording.slice(0, 1500)
    time = 1234.5 + np.arange(len(r)) * 1e-3
    got = run_estimator_fmu(time, r.i_m, r.theta_m, r.theta_l, estimator_params)
    ref = paper_ukf(estimator_params, r.i_m, r.theta_m, r.theta_l)
    for name, tol in (("tau_ukf", TOL_TORQUE), ("tau_ukf_std", TOL_TORQUE), ("omega_m", TOL_SPEED),
                      ("tau_compliance", TOL_TORQUE)):
        assert max_abs_diff(got[name], ref[name]) <= tol, name


@pytest.mark.parametrize("theta_l0, tau_ext", [(0.5, 0.3), (-1.0, 2.0), (1.2, -8.0)])
def test_joint_at_rest_and_estimator_compliance_agree(theta_l0, tau_ext, make_slave, default_params,
                                                      estimator_params):
    """A joint held at rest under gravity and a load: the transmitted torque is mgl*sin(theta_l0) + tau_ext,
    and the compliance model (tau_w = Kt*i_m = tau/N at rest) recovers it from the joint's encoders."""
    plant_params = parameters.for_plant({**default_params, "theta_l0": theta_l0, "motor_counts": 0.0,
                                         "link_counts": 0.0})
    tau = default_params["mgl"] * np.sin(theta_l0) + tau_ext
    i_hold = tau / (default_params["N"] * default_params["Kt"])  # no friction at rest
    joint = make_slave("HarmonicDriveJoint", "joint")
    joint.start(params=plant_params, inputs={"i_m": i_hold, "tau_ext": tau_ext})
    out = joint.run(0.0, [1e-3] * 200, np.tile([i_hold, tau_ext], (200, 1)), ("i_m", "tau_ext"),
                    ("theta_m", "theta_l", "tau_joint", "omega_m", "omega_link"))
    assert np.abs(out[:, 2] - tau).max() <= 1e-9 * max(1.0, abs(tau))  # stays in equilibrium
    assert np.abs(out[:, 3:]).max() <= 1e-9
    assert np.abs(out[:, 1] - theta_l0).max() <= 1e-12
    theta_m, theta_l = out[-1, 0], out[-1, 1]

    _, tau_oracle = compliance(estimator_params, i_hold, theta_m, theta_l)
    assert abs(float(tau_oracle) - tau) <= 1e-9 * max(1.0, abs(tau))
    est = make_slave("JointTorqueEstimator", "estimator")
    est.start(inputs={"i_m": i_hold, "theta_m": theta_m, "theta_l": theta_l})
    est.slave.doStep(0.0, 1e-3)
    assert abs(est.get(["tau_compliance"])[0] - tau) <= 1e-9 * max(1.0, abs(tau))
