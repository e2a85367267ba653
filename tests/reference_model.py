"""Independent numpy implementations of the paper's models, used as test oracles.

Written straight from the equations in CONTRACT.md and the project's UKF
definition (not from the C++ sources), so that agreement with the C++ code
means something.  Deliberately plain: generic scipy matrix exponential and
Cholesky, one loop over samples, no cleverness.

Parameters are a plain dict ``p`` with the FMU parameter names.
"""

import numpy as np
import scipy.linalg

# A SHD-17-100-class joint and the UKF settings the tests use.
DEFAULTS = {
    "N": 100, "Kt": 0.045, "Jm": 2.09e-5, "Bm": 3e-5,
    "Fc": 0.015, "omega_fc": 1.0,
    "Kf": 1e4, "Cf": 0.0645, "Kw": 10, "Cw": 10,
    "a0": 0, "al1": 1e-4, "bl1": 0.5e-4, "omega_l": 1,
    "aw1": 0.6e-4, "bw1": -0.4e-4, "aw2": 0.2e-4, "bw2": 0.1e-4, "omega_w": 2,
    "Ts": 1e-3,
    "ukf_alpha": 1, "ukf_beta": 2, "ukf_kappa": 1,
    "ukf_q_omega": 0.05, "ukf_q_tau": 0.02,
    "ukf_r_omega": 0.9, "ukf_r_torsion": 6e-6,
    "ukf_p0_omega": 1, "ukf_p0_tau": 1,
}

UKF_OUTPUTS = ("tau_ukf", "tau_compliance", "omega_m", "dtheta_f",
               "tau_ukf_std", "nis")


# ------------------------------------------------------------ compliance model


def kinematic_error(p, theta_m, theta_l):
    """Eq. (7): transmission error; the wave generator angle is theta_m."""
    wl, ww = p["omega_l"], p["omega_w"]
    return (p["a0"]
            + p["al1"] * np.cos(wl * theta_l) + p["bl1"] * np.sin(wl * theta_l)
            + p["aw1"] * np.cos(ww * theta_m) + p["bw1"] * np.sin(ww * theta_m)
            + p["aw2"] * np.cos(2 * ww * theta_m) + p["bw2"] * np.sin(2 * ww * theta_m))


def wave_generator_torsion(p, tau):
    """Eq. (3): wg(tau), with its Cw -> 0 limit tau/(N*Kw)."""
    tau = np.asarray(tau, dtype=float)
    N, Kw, Cw = p["N"], p["Kw"], p["Cw"]
    if Cw == 0:
        return tau / (N * Kw)
    # -expm1(-x) is 1 - exp(-x) without cancellation when Cw*|tau| is tiny.
    return np.sign(tau) / (Cw * N * Kw) * -np.expm1(-Cw * np.abs(tau))


def torque_from_torsion(p, dtheta_f):
    """Eq. (8): flexspline torque from its torsion (Cf -> 0: linear spring)."""
    Cf, Kf = p["Cf"], p["Kf"]
    if Cf == 0:
        return Kf * dtheta_f
    return np.tan(Cf * Kf * dtheta_f) / Cf


def torsion_from_torque(p, tau_f):
    """Eq. (5): flexspline torsion from its torque; the inverse of eq. (8)."""
    Cf, Kf = p["Cf"], p["Kf"]
    if Cf == 0:
        return tau_f / Kf
    return np.arctan(Cf * tau_f) / (Cf * Kf)


def compliance(p, i_m, theta_m, theta_l):
    """Eqs. (3)-(8): returns (dtheta_f, tau_compliance), vectorised."""
    i_m, theta_m, theta_l = (np.asarray(a, dtype=float) for a in (i_m, theta_m, theta_l))
    dtheta = theta_m / p["N"] - theta_l
    dtheta_f = (dtheta - wave_generator_torsion(p, p["Kt"] * i_m)
                - kinematic_error(p, theta_m, theta_l))
    return dtheta_f, torque_from_torsion(p, dtheta_f)


# ------------------------------------------------------------ the paper's UKF


def ukf_weights(p, n=2):
    """Van der Merwe scaled weights: (Wm, Wc, gamma)."""
    alpha, beta, kappa = p["ukf_alpha"], p["ukf_beta"], p["ukf_kappa"]
    lam = alpha**2 * (n + kappa) - n
    Wm = np.full(2 * n + 1, 1.0 / (2 * (n + lam)))
    Wc = Wm.copy()
    Wm[0] = lam / (n + lam)
    Wc[0] = Wm[0] + 1 - alpha**2 + beta
    return Wm, Wc, np.sqrt(n + lam)


def sigma_points(x, P, gamma):
    """Rows: x, x + gamma*L[:, i] for each i, then x - gamma*L[:, i]."""
    L = scipy.linalg.cholesky(_sym(P), lower=True)
    plus = [x + gamma * L[:, i] for i in range(len(x))]
    minus = [x - gamma * L[:, i] for i in range(len(x))]
    return np.array([x] + plus + minus)


def discrete_motor_model(p):
    """Zero-order-hold discretisation (F, G) of the motor + constant torque state."""
    N, Jm, Bm, Ts = p["N"], p["Jm"], p["Bm"], p["Ts"]
    A = np.array([[-Bm / Jm, -1.0 / (N * Jm)], [0.0, 0.0]])
    B = np.array([[1.0 / Jm], [0.0]])
    M = np.zeros((3, 3))
    M[:2, :2] = A
    M[:2, 2:] = B
    E = scipy.linalg.expm(M * Ts)
    return E[:2, :2], E[:2, 2]


def measurement(p, x):
    """h(x): measured motor speed and flexspline torsion."""
    return np.array([x[0], torsion_from_torque(p, x[1])])


def coulomb_friction(p, omega):
    """Nominal motor friction tau_fm, smoothed through zero."""
    return p["Fc"] * np.tanh(omega / p["omega_fc"])


def _sym(P):
    return (P + P.T) / 2


def _weighted_cov(Wc, A, B):
    """sum_i Wc[i] * A[i] B[i]^T for row-stacked deviations A, B."""
    return (A * Wc[:, None]).T @ B


def paper_ukf(p, i_m, theta_m, theta_l):
    """Run the project's definition of the paper's UKF over a recording.

    Returns a dict of arrays: tau_ukf, tau_compliance, omega_m, dtheta_f,
    tau_ukf_std, nis (normalised innovation squared).
    """
    i_m, theta_m, theta_l = (np.asarray(a, dtype=float) for a in (i_m, theta_m, theta_l))
    n_samples = len(i_m)
    Ts = p["Ts"]
    Wm, Wc, gamma = ukf_weights(p)
    F, G = discrete_motor_model(p)
    Q = np.diag([p["ukf_q_omega"] ** 2, p["ukf_q_tau"] ** 2])
    R = np.diag([p["ukf_r_omega"] ** 2, p["ukf_r_torsion"] ** 2])
    P0 = np.diag([p["ukf_p0_omega"] ** 2, p["ukf_p0_tau"] ** 2])

    dtheta_f, tau_c = compliance(p, i_m, theta_m, theta_l)
    out = {key: np.empty(n_samples) for key in UKF_OUTPUTS}
    x, P, u_prev = None, None, None
    for k in range(n_samples):
        # 2. initialise, or predict through the motor model.
        if k == 0:
            x = np.array([0.0, tau_c[0]])
            P = P0.copy()
            speed = 0.0
        else:
            chi = sigma_points(x, P, gamma) @ F.T + G * u_prev
            x = Wm @ chi
            P = _sym(_weighted_cov(Wc, chi - x, chi - x) + Q)
            speed = (theta_m[k] - theta_m[k - 1]) / Ts

        # 3. update with the measured speed and flexspline torsion.
        z = np.array([speed, dtheta_f[k]])
        chi = sigma_points(x, P, gamma)
        Z = np.array([measurement(p, c) for c in chi])
        zhat = Wm @ Z
        Pzz = _sym(_weighted_cov(Wc, Z - zhat, Z - zhat) + R)
        Pxz = _weighted_cov(Wc, chi - x, Z - zhat)
        K = np.linalg.solve(Pzz.T, Pxz.T).T  # Pxz @ inv(Pzz)
        nu = z - zhat
        x = x + K @ nu
        P = _sym(P - K @ Pzz @ K.T)

        # 4. outputs.
        out["tau_ukf"][k] = x[1]
        out["omega_m"][k] = x[0]
        out["tau_ukf_std"][k] = np.sqrt(P[1, 1])
        out["nis"][k] = nu @ np.linalg.solve(Pzz, nu)

        # 5. input for the next prediction, friction at the posterior speed.
        u_prev = p["Kt"] * i_m[k] - coulomb_friction(p, x[0])

    out["tau_compliance"] = tau_c
    out["dtheta_f"] = dtheta_f
    return out
