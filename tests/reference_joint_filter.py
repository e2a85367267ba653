"""Independent numpy/scipy implementation of the joint-state filter and its
RTS smoother (tau_hat, tau_smooth), a test oracle for the C++ code.

Written from the model as documented in joint_state_filter.h and the README
(state [theta_l, omega_l, delta, nu, w, r, g, e, s], two-mass dynamics driven by
the current (its sensor's gain error undone by s), linearly implicit trapezoidal step, floor-quantised encoder
readings), not from the C++ sources. Deliberately different in method where
it can be: the Jacobian of the dynamics comes from complex-step
differentiation (exact to round-off) instead of hand-derived partials, the
step solves with scipy, the update is the textbook Kalman update.

Covers the paper's model without the beyond-the-paper terms (the default
parameter set), as reference_model.py does.
"""
import numpy as np
import scipy.linalg

from reference_model import kinematic_error, torque_from_torsion, wave_generator_torsion

TWO_PI = 2 * np.pi
# Initial spreads of the states the first reading does not fix (as documented).
P0_ANGLE, P0_TORSION, P0_SPEED = 1e-2, 1e-3, 0.1
# The link inertia's relative error g: its prior deviation and random walk per sample (as documented).
P0_INERTIA, Q_INERTIA = 0.1, 1e-5
# The compliance model's error e: its prior is what its walk spreads in a second, at least 1e-6 N.m.
MIN_TORQUE_ERROR_STD = 1e-6
# The current sensor's gain error s: prior jsf_current_gain (at least 1e-9); its variance grows by the
# prior's over CURRENT_DRIFT_TIME (as documented).
MIN_CURRENT_GAIN_STD, CURRENT_DRIFT_TIME = 1e-9, 600.0
N_STATES = 9


def kinematic_error_rate(p, theta_m, theta_l, omega_m, omega_l):
    """d/dt of eq. (7)'s kinematic error along the motion (its terms differentiated by hand)."""
    wl, ww = p["omega_l"], p["omega_w"]
    by_link = wl * (-p["al1"] * np.sin(wl * theta_l) + p["bl1"] * np.cos(wl * theta_l))
    by_motor = ww * (-p["aw1"] * np.sin(ww * theta_m) + p["bw1"] * np.cos(ww * theta_m)
                     - 2 * p["aw2"] * np.sin(2 * ww * theta_m) + 2 * p["bw2"] * np.cos(2 * ww * theta_m))
    return by_link * omega_l + by_motor * omega_m


def joint_torque(p, x, i_m):
    """Transmitted torque of a state, the compliance model plus its error e and the structural damping of
    the elastic torsion rate, nu less the kinematic error's rate (works for complex x: complex-step)."""
    theta_l, omega_l, delta, nu = x[0], x[1], x[2], x[3]
    theta_m = p["N"] * (theta_l + delta)
    dtheta_f = delta - wave_generator_torsion(p, p["Kt"] * i_m) - kinematic_error(p, theta_m, theta_l)
    damping = p.get("Df", 0.0) * (nu - kinematic_error_rate(p, theta_m, theta_l, p["N"] * (omega_l + nu), omega_l))
    return torque_from_torsion(p, dtheta_f) + damping + x[7]


def dynamics(p, x, i_m):
    theta_l, omega_l, delta, nu, w, rate, g, e, s = x
    tau = joint_torque(p, x, i_m)
    omega_m = p["N"] * (omega_l + nu)
    friction = p["Fc"] * np.tanh(omega_m / p["omega_fc"]) + p["Bm"] * omega_m
    link_acc = (tau - p["Bl"] * omega_l - p["mgl"] * np.sin(theta_l) - w) / (p["Jl"] * (1 + g))
    motor_acc = (p["Kt"] * (1 + s) * i_m - friction - tau / p["N"]) / (p["N"] * p["Jm"])  # of omega_l + nu
    return np.array([omega_l, link_acc, nu, motor_acc - link_acc, rate, 0.0 * w, 0.0 * g, 0.0 * e, 0.0 * s])


def complex_step_jacobian(fun, x, h=1e-30):
    n = len(x)
    J = np.empty((len(fun(x.astype(complex))), n))
    for k in range(n):
        dx = np.zeros(n, complex)
        dx[k] = 1j * h
        J[:, k] = np.imag(fun(x + dx)) / h
    return J


def torque_gradient(p, x, i_m):
    return complex_step_jacobian(lambda y: np.array([joint_torque(p, y, i_m)]), x)[0]


def transition(p, x, i_m):
    """Linearly implicit trapezoidal step: (next state, F)."""
    h = p["Ts"]
    f = dynamics(p, x, i_m)
    J = complex_step_jacobian(lambda y: dynamics(p, y, i_m), x)
    M = np.eye(N_STATES) - 0.5 * h * J
    return x + scipy.linalg.solve(M, h * f), scipy.linalg.solve(M, np.eye(N_STATES) + 0.5 * h * J)


def motor_noise_shape(p):
    """G G^T of a motor torque held over a sample, in (omega_l + nu) acceleration per N.m."""
    h = p["Ts"]
    G = np.array([0.0, 0.0, h * h / 2, h, 0.0, 0.0, 0.0, 0.0, 0.0]) / (p["N"] * p["Jm"])
    return np.outer(G, G)


# Counts of each encoder within which an imbalance at rest is not taken as friction (as documented).
REST_FRICTION_COUNTS = 1.5


def rest_friction_noise(p, x, i_m):
    """The friction the law misses at rest (jsf_q_stiction): the motor torque the spring's torque leaves
    unbalanced beyond REST_FRICTION_COUNTS of each encoder, fading as sech^2(omega_m/omega_fc)."""
    omega_m = p["N"] * (x[1] + x[3])
    friction = p["Fc"] * np.tanh(omega_m / p["omega_fc"]) + p["Bm"] * omega_m
    held = p["Kt"] * (1 + x[8]) * i_m - friction - (joint_torque(p, x, i_m) - x[7]) / p["N"]
    g = torque_gradient(p, x, i_m)
    qm, ql = TWO_PI / p["motor_counts"], TWO_PI / p["link_counts"]
    hidden = REST_FRICTION_COUNTS * (abs(g[2]) * qm / p["N"] + abs(g[0] - g[2]) * ql)
    std = p["jsf_q_stiction"] * max(0.0, abs(held) - hidden / p["N"]) / np.cosh(omega_m / p["omega_fc"]) ** 2
    return std * std * motor_noise_shape(p)


def averaged_friction(p, P):
    """The parameters with the Coulomb law the prediction uses: tanh(w/a) averaged over the motor speed's
    spread in P, a Gaussian: the law with a^2 + (pi/2) Var(omega_m) (as documented)."""
    var_omega_m = p["N"] ** 2 * max(0.0, P[1, 1] + 2 * P[1, 3] + P[3, 3])
    return {**p, "omega_fc": np.sqrt(p["omega_fc"] ** 2 + np.pi / 2 * var_omega_m)}


def noise(p):
    Q = (p["Kt"] * p["jsf_current_noise"]) ** 2 * motor_noise_shape(p) + p["jsf_q_motor"] ** 2 * motor_noise_shape(p)
    Q[4, 4] += p["jsf_q_load"] ** 2
    Q[5, 5] += p["jsf_q_load_rate"] ** 2
    Q[6, 6] += Q_INERTIA ** 2
    Q[7, 7] += p["jsf_q_torque"] ** 2
    Q[8, 8] += p["jsf_current_gain"] ** 2 * p["Ts"] / CURRENT_DRIFT_TIME
    qm = TWO_PI / p["motor_counts"] if p["motor_counts"] > 0 else 0.0
    ql = TWO_PI / p["link_counts"] if p["link_counts"] > 0 else 0.0
    R = np.diag([max(p["jsf_r_theta_m"] ** 2 + qm * qm / 12, 1e-24), max(p["jsf_r_theta_l"] ** 2 + ql * ql / 12, 1e-24)])
    return Q, R, np.array([qm / 2, ql / 2]), np.array([qm * qm / 12, ql * ql / 12])


# A reading equal to the one before repeats its quantisation error: the k-th
# repeat's quantisation variance is (1 + REPEAT_WEIGHT*k) q^2/12 (as documented).
REPEAT_WEIGHT = 0.02


def repeats(readings):
    """How many readings just before each one are equal to it."""
    count = np.zeros(len(readings))
    for k in range(1, len(readings)):
        count[k] = count[k - 1] + 1 if readings[k] == readings[k - 1] else 0
    return count


def unseen_variance(p):
    """The current sensor's offset on the transmitted torque, N*Kt*jsf_current_offset, as a variance: no state
    can tell it from a compliance error (as documented)."""
    return (p["N"] * p["Kt"] * p["jsf_current_offset"]) ** 2


def joint_filter(p, i_m, theta_m, theta_l):
    """Filter over samples; returns tau_hat, tau_hat_std and what the smoother needs."""
    n = len(i_m)
    Q, R0, offset, quantisation = noise(p)
    repeated = np.column_stack([repeats(theta_m), repeats(theta_l)])
    H = np.array([[p["N"], 0, p["N"], 0, 0, 0, 0, 0, 0], [1.0, 0, 0, 0, 0, 0, 0, 0, 0]])
    out = {"tau_hat": np.empty(n), "tau_hat_std": np.empty(n)}
    store = {"x": [], "P": [], "x_prior": [], "P_prior": [], "F": []}
    x = P = None
    for k in range(n):
        z = np.array([theta_m[k], theta_l[k]]) + offset
        if k == 0:
            x = np.zeros(N_STATES)
            x[0] = z[1]
            x[2] = z[0] / p["N"] - z[1]
            x[4] = joint_torque(p, x, i_m[0]) - p["mgl"] * np.sin(x[0])
            P = np.diag([P0_ANGLE**2, P0_SPEED**2, P0_TORSION**2, P0_SPEED**2, p["jsf_p0_load"] ** 2,
                         p["jsf_p0_load"] ** 2, P0_INERTIA**2,
                         max(p["jsf_q_torque"] / np.sqrt(p["Ts"]), MIN_TORQUE_ERROR_STD) ** 2,
                         max(p["jsf_current_gain"], MIN_CURRENT_GAIN_STD) ** 2])
            F = np.eye(N_STATES)
        else:
            averaged = averaged_friction(p, P)
            Q_rest = rest_friction_noise(averaged, x, i_m[k - 1])
            x, F = transition(averaged, x, i_m[k - 1])
            P = F @ P @ F.T + Q + Q_rest
        store["x_prior"].append(x.copy())
        store["P_prior"].append(P.copy())
        store["F"].append(F)
        R = R0 + np.diag(REPEAT_WEIGHT * repeated[k] * quantisation)
        if k > 0:  # readings taken off their sample time move along the angles' rates (as documented)
            rates = np.array([p["N"] * (x[1] + x[3]), x[1]])
            R = R + p["jsf_r_time"] ** 2 * np.outer(rates, rates)
        S = H @ P @ H.T + R
        K = P @ H.T @ np.linalg.inv(S)
        x = x + K @ (z - H @ x)
        P = P - K @ S @ K.T
        P = (P + P.T) / 2
        store["x"].append(x.copy())
        store["P"].append(P.copy())
        g = torque_gradient(p, x, i_m[k])
        out["tau_hat"][k] = joint_torque(p, x, i_m[k])
        out["tau_hat_std"][k] = np.sqrt(g @ P @ g + unseen_variance(p))
    return out, store


def rts_smoother(p, i_m, store):
    """Rauch-Tung-Striebel over the stored filter: tau_smooth, tau_smooth_std."""
    n = len(store["x"])
    xs, Ps = store["x"][-1], store["P"][-1]
    tau, std = np.empty(n), np.empty(n)
    for k in range(n - 1, -1, -1):
        if k < n - 1:
            C = store["P"][k] @ store["F"][k + 1].T @ np.linalg.inv(store["P_prior"][k + 1])
            xs = store["x"][k] + C @ (xs - store["x_prior"][k + 1])
            Ps = store["P"][k] + C @ (Ps - store["P_prior"][k + 1]) @ C.T
        g = torque_gradient(p, xs, i_m[k])
        tau[k] = joint_torque(p, xs, i_m[k])
        std[k] = np.sqrt(g @ Ps @ g + unseen_variance(p))
    return tau, std
