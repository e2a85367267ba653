"""Self-checks of the numpy oracles in reference_model.py."""

import numpy as np
import pytest

import reference_model as rm
from reference_model import DEFAULTS


def params(**changes):
    p = dict(DEFAULTS)
    p.update(changes)
    return p


def synthetic_joint(p, tau0, duration=1.0, noise=True, seed=0):
    """Motor speed profile under a constant joint torque tau0, sampled at Ts.

    Current follows from eq. (2); the link angle from the compliance model
    inverted (fixed point: theta_err depends only weakly on theta_l).
    Returns (i_m, theta_m, theta_l, omega_true).
    """
    Ts = p["Ts"]
    t = np.arange(int(round(duration / Ts))) * Ts
    w = np.pi  # 0.5 Hz speed ripple
    omega = 20 + 10 * np.sin(w * t)
    domega = 10 * w * np.cos(w * t)
    theta_m = 20 * t + 10 / w * (1 - np.cos(w * t))
    i_m = (p["Jm"] * domega + p["Bm"] * omega + rm.coulomb_friction(p, omega)
           + tau0 / p["N"]) / p["Kt"]
    twist = rm.torsion_from_torque(p, tau0) + rm.wave_generator_torsion(p, p["Kt"] * i_m)
    theta_l = theta_m / p["N"] - twist
    for _ in range(5):
        theta_l = theta_m / p["N"] - twist - rm.kinematic_error(p, theta_m, theta_l)
    if noise:
        rng = np.random.default_rng(seed)
        i_m = i_m + rng.normal(0, 0.005, i_m.shape)
        step = 2 * np.pi / 2**17  # 17-bit motor encoder
        theta_m = np.round(theta_m / step) * step
        theta_l = theta_l + rng.normal(0, 1e-6, theta_l.shape)
    return i_m, theta_m, theta_l, omega


# ------------------------------------------------------------ compliance


def test_compliance_tends_to_linear_limit():
    i_m, theta_m, theta_l, _ = synthetic_joint(params(), tau0=8.0, noise=False)
    i_m = i_m + np.linspace(-2, 2, len(i_m))  # cover both signs of wg
    lin_f, lin_tau = rm.compliance(params(Cf=0, Cw=0), i_m, theta_m, theta_l)
    tiny_f, tiny_tau = rm.compliance(params(Cf=1e-12, Cw=1e-12), i_m, theta_m, theta_l)
    np.testing.assert_allclose(tiny_f, lin_f, rtol=1e-9, atol=1e-9 * np.abs(lin_f).max())
    np.testing.assert_allclose(tiny_tau, lin_tau, rtol=1e-9,
                               atol=1e-9 * np.abs(lin_tau).max())


def test_compliance_by_hand():
    # No transmission error, no current: the torsion is the plain twist.
    p = params(al1=0, bl1=0, aw1=0, bw1=0, aw2=0, bw2=0)
    dtheta_f, tau = rm.compliance(p, 0.0, 1.0, 1.0 / 100 - 2e-4)
    assert dtheta_f == pytest.approx(2e-4, rel=1e-9)
    assert tau == pytest.approx(np.tan(0.0645 * 1e4 * 2e-4) / 0.0645, rel=1e-12)
    # Positive current twists the wave generator, leaving less for the flexspline.
    dtheta_f2, _ = rm.compliance(p, 1.0, 1.0, 1.0 / 100 - 2e-4)
    wg = (1 - np.exp(-10 * 0.045)) / (10 * 100 * 10)
    assert dtheta_f2 == pytest.approx(2e-4 - wg, rel=1e-9)


def test_torsion_and_torque_are_inverse():
    tau = np.linspace(-30, 30, 61)
    back = rm.torque_from_torsion(DEFAULTS, rm.torsion_from_torque(DEFAULTS, tau))
    np.testing.assert_allclose(back, tau, rtol=1e-12, atol=1e-12)


# ------------------------------------------------------------ UKF


def linear_kalman_filter(p, i_m, theta_m, dtheta_f, tau_c):
    """Plain KF for the Cf = 0 case, with the ZOH model in closed form."""
    a, b, Jm, Ts = p["Bm"] / p["Jm"], 1 / (p["N"] * p["Jm"]), p["Jm"], p["Ts"]
    e = np.exp(-a * Ts)
    F = np.array([[e, -b * (1 - e) / a], [0, 1]])
    G = np.array([(1 - e) / (a * Jm), 0])
    H = np.diag([1, 1 / p["Kf"]])
    Q = np.diag([p["ukf_q_omega"], p["ukf_q_tau"]]) ** 2
    R = np.diag([p["ukf_r_omega"], p["ukf_r_torsion"]]) ** 2
    x, P = np.array([0, tau_c[0]]), np.diag([p["ukf_p0_omega"], p["ukf_p0_tau"]]) ** 2
    rows = []
    for k in range(len(i_m)):
        speed = 0.0
        if k > 0:
            x, P = F @ x + G * u, F @ P @ F.T + Q
            speed = (theta_m[k] - theta_m[k - 1]) / Ts
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        nu = np.array([speed, dtheta_f[k]]) - H @ x
        x, P = x + K @ nu, P - K @ S @ K.T
        rows.append((x[1], x[0], np.sqrt(P[1, 1]), nu @ np.linalg.inv(S) @ nu))
        u = p["Kt"] * i_m[k] - p["Fc"] * np.tanh(x[0] / p["omega_fc"])
    return dict(zip(("tau_ukf", "omega_m", "tau_ukf_std", "nis"), np.array(rows).T))


def test_ukf_equals_kalman_filter_for_linear_measurement():
    p = params(Cf=0)
    i_m, theta_m, theta_l, _ = synthetic_joint(p, tau0=5.0, duration=0.3)
    ukf = rm.paper_ukf(p, i_m, theta_m, theta_l)
    dtheta_f, tau_c = rm.compliance(p, i_m, theta_m, theta_l)
    kf = linear_kalman_filter(p, i_m, theta_m, dtheta_f, tau_c)
    for key, expected in kf.items():
        np.testing.assert_allclose(ukf[key], expected, rtol=1e-9,
                                   atol=1e-9 * np.abs(expected).max(), err_msg=key)
    np.testing.assert_array_equal(ukf["dtheta_f"], dtheta_f)
    np.testing.assert_array_equal(ukf["tau_compliance"], tau_c)


def test_ukf_tracks_constant_torque():
    p = params()
    tau0 = 6.0
    i_m, theta_m, theta_l, omega = synthetic_joint(p, tau0=tau0, duration=2.0)
    out = rm.paper_ukf(p, i_m, theta_m, theta_l)
    assert set(out) == set(rm.UKF_OUTPUTS)
    assert all(v.shape == i_m.shape for v in out.values())
    settled = slice(200, None)  # after 0.2 s
    err = out["tau_ukf"][settled] - tau0
    # Observed: mean ~1e-4, RMS ~0.004 N.m; a sign error in the model's load
    # term gives ~0.56 N.m, so these bounds separate right from wrong.
    assert abs(err.mean()) < 0.005
    assert np.sqrt(np.mean(err**2)) < 0.015
    # The filter smooths: its estimate is steadier than the raw compliance torque.
    assert err.std() < (out["tau_compliance"][settled] - tau0).std()
    speed_err = out["omega_m"][settled] - omega[settled]
    assert np.sqrt(np.mean(speed_err**2)) < 0.15
    assert np.all(out["tau_ukf_std"] > 0)
    assert np.all(out["nis"] >= 0)
