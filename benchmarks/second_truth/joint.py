"""The second truth's joint: motor, harmonic drive and link as one ODE.

Signs and compliance follow the project contract (/work/shared/CONTRACT.md),
i.e. Yu et al. 2018 eq. (2)-(8) with the flexspline reversal taken out:
  dtheta = theta_m/N - theta_l,  dtheta_f = dtheta - wg(tau_w) - theta_err,
  Jm*dw_m/dt + Bm*w_m + tau_fm + tau_f/N = Kt*i + (motor-torque forms),
  Jl*dw_l/dt = tau_f - Bl*w_l - mgl*sin(theta_l) - tau_ext.
Unlike the estimator's approximation tau_w = Kt*i_m, the wave generator here
carries the transmitted torque's share tau_w = tau_f/N (solved by Newton).
The torsion q = theta_m/N - theta_l is integrated as a state itself, so the
small difference of two large angles is never formed (theta_m reaches
hundreds of rad, the torsion is 1e-4 rad). The current loop is a first-order
lag behind the drive's held command. Approximations: the transmission forms
(damping, hysteresis) see the torsion rate without the wave generator's
share, add to the torque outside the Newton loop, and act only in contact
(outside a backlash's dead zone).
State: [theta_l, omega_l, q, omega_m, i, form states...].
"""
from __future__ import annotations

import math

import numpy as np


class Ctx:
    """What a form sees of the joint at one instant."""
    __slots__ = ("t", "theta_l", "omega_l", "q", "omega_m", "theta_m", "i", "x", "xdot",
                 "contact", "tau_el", "tau_f", "p")


def wg(tau_w: float, N: float, Kw: float, Cw: float) -> tuple[float, float]:
    """Contract eq. (4) wave generator deflection (motor side over N) and its slope in tau_w."""
    if not Kw or math.isinf(Kw):
        return 0.0, 0.0
    if Cw <= 0.0:
        return tau_w / (N * Kw), 1.0 / (N * Kw)
    e = math.exp(-Cw * abs(tau_w))
    return math.copysign(1.0 - e, tau_w) / (Cw * N * Kw), e / (N * Kw)


def dead_zone(x: float, width: float) -> tuple[float, float]:
    """Lost motion: no torque inside +-width/2 (returns value and slope)."""
    h = 0.5 * width
    if h <= 0.0:
        return x, 1.0
    if x > h:
        return x - h, 1.0
    if x < -h:
        return x + h, 1.0
    return 0.0, 0.0


class Joint:
    """One joint: true parameters `p` plus its forms (torque roles only)."""

    def __init__(self, p: dict, forms: list):
        self.p = dict(p)
        self.forms = [f for f in forms if f.role in ("motor_friction", "transmission", "motor_torque", "stiffness")]
        stiff = [f for f in self.forms if f.role == "stiffness"]
        if len(stiff) != 1:
            raise ValueError("a joint needs exactly one stiffness form")
        self.stiffness = stiff[0]
        self.friction = [f for f in self.forms if f.role == "motor_friction"]
        self.transmission = [f for f in self.forms if f.role == "transmission"]
        self.motor_torque = [f for f in self.forms if f.role == "motor_torque"]
        for f in self.forms:
            if hasattr(f, "bind"):
                f.bind(self.p)
        self.dyn = [f for f in self.forms if f.n_states]
        self.slices = []
        k = 5
        for f in self.dyn:
            self.slices.append(slice(k, k + f.n_states))
            k += f.n_states
        self.n = k
        self._tau_guess = 0.0
        self.ctx = Ctx()
        self.ctx.p = self.p

    # ---- kinematic error, contract eq. (7) plus extra harmonics -----------
    def theta_err(self, theta_m: float, theta_l: float, omega_m: float, omega_l: float) -> tuple[float, float]:
        p = self.p
        val = p["a0"]
        rate = 0.0
        terms = [(theta_l, omega_l, p["omega_l"], p["al1"], p["bl1"]),
                 (theta_m, omega_m, p["omega_w"], p["aw1"], p["bw1"]),
                 (theta_m, omega_m, 2.0 * p["omega_w"], p["aw2"], p["bw2"])]
        for axis, order, a, b in p.get("harmonics", ()):
            terms.append((theta_m, omega_m, order, a, b) if axis == "m" else (theta_l, omega_l, order, a, b))
        for ang, w, order, a, b in terms:
            c, s = math.cos(order * ang), math.sin(order * ang)
            val += a * c + b * s
            rate += order * w * (b * c - a * s)
        return val, rate

    def transmitted(self, x0: float) -> tuple[float, float, float]:
        """Elastic flexspline torque for the torsion x0 (kinematic error removed):
        solves tau = E(deadzone(x0 - wg(tau/N))) by Newton. Returns (tau, x_f, contact)."""
        p = self.p
        N, Kw, Cw, b = p["N"], p.get("Kw", 0.0), p.get("Cw", 0.0), p.get("backlash", 0.0)
        E = self.stiffness.elastic
        if not Kw and b <= 0.0:
            return E(x0)[0], x0, 1.0
        tau = self._tau_guess
        for _ in range(12):
            w, dw = wg(tau / N, N, Kw, Cw)
            xf, ddz = dead_zone(x0 - w, b)
            e, k = E(xf)
            f = tau - e
            fp = 1.0 + k * ddz * dw / N
            step = f / fp
            tau -= step
            if abs(step) < 1e-11 * (1.0 + abs(tau)):
                break
        w, _ = wg(tau / N, N, Kw, Cw)
        xf, ddz = dead_zone(x0 - w, b)
        tau, _ = E(xf)
        self._tau_guess = tau
        return tau, xf, ddz

    def evaluate(self, t: float, y, i_cmd: float, tau_ext: float = 0.0):
        """Fill the context and return the state derivative."""
        p, c = self.p, self.ctx
        N = p["N"]
        theta_l, omega_l, q, omega_m, i = y[0], y[1], y[2], y[3], y[4]
        theta_m = N * (theta_l + q)
        qdot = omega_m / N - omega_l
        terr, terr_rate = self.theta_err(theta_m, theta_l, omega_m, omega_l)
        tau_el, xf, contact = self.transmitted(q - terr)
        c.t, c.theta_l, c.omega_l, c.q, c.omega_m, c.theta_m, c.i = t, theta_l, omega_l, q, omega_m, theta_m, i
        c.x, c.xdot, c.contact, c.tau_el = xf, (qdot - terr_rate) * contact, contact, tau_el
        zs = [y[s] for s in self.slices]
        zmap = {id(f): z for f, z in zip(self.dyn, zs)}
        tau_f = tau_el
        for f in self.transmission:
            tau_f += contact * f.torque(c, zmap.get(id(f)))
        c.tau_f = tau_f
        fric = sum(f.torque(c, zmap.get(id(f))) for f in self.friction)
        drive = p["Kt"] * i + sum(f.torque(c, zmap.get(id(f))) for f in self.motor_torque)
        domega_m = (drive - p["Bm"] * omega_m - fric - tau_f / N) / p["Jm"]
        domega_l = (tau_f - p["Bl"] * omega_l - p["mgl"] * math.sin(theta_l) - tau_ext) / p["Jl"]
        di = (i_cmd - i) / p["tau_i"]
        out = [omega_l, domega_l, qdot, domega_m, di]
        for f, z in zip(self.dyn, zs):
            out.extend(f.rates(c, z))
        return out

    def rhs(self, t, y, i_cmd, tau_ext=0.0):
        return np.asarray(self.evaluate(t, y, i_cmd, tau_ext))

    def tau_f(self, t, y) -> float:
        """Transmitted torque (what a torque sensor reads) in state y."""
        self.evaluate(t, y, 0.0)
        return self.ctx.tau_f

    def atol(self) -> np.ndarray:
        tol = [1e-9, 1e-7, 1e-11, 1e-6, 1e-6]
        for f in self.dyn:
            tol.extend(f.state_atol or [1e-9] * f.n_states)
        return np.asarray(tol)

    def rest_state(self, theta_l0: float, tau_ext: float = 0.0) -> tuple[np.ndarray, float]:
        """The joint at rest in static equilibrium at theta_l0: tau_f = mgl*sin(theta_l0) + tau_ext.
        Returns the state and the current that holds it (friction and forms' states at zero)."""
        p = self.p
        N = p["N"]
        tau = p["mgl"] * math.sin(theta_l0) + tau_ext
        xf = self.stiffness.inverse(tau)
        b = p.get("backlash", 0.0)
        x0 = xf + (math.copysign(0.5 * b, tau) if tau != 0.0 else 0.0)
        x0 += wg(tau / N, N, p.get("Kw", 0.0), p.get("Cw", 0.0))[0]
        q = x0
        for _ in range(20):
            terr, _ = self.theta_err(N * (theta_l0 + q), theta_l0, 0.0, 0.0)
            q = x0 + terr
        y = np.zeros(self.n)
        y[0], y[2] = theta_l0, q
        self._tau_guess = tau
        c = self.ctx
        c.t, c.theta_l, c.omega_l, c.q, c.omega_m, c.theta_m, c.i = 0.0, theta_l0, 0.0, q, 0.0, N * (theta_l0 + q), 0.0
        c.x, c.xdot, c.contact, c.tau_el, c.tau_f = xf, 0.0, 1.0, tau, tau
        cog = sum(f.torque(c, None) for f in self.motor_torque)
        i0 = (tau / N - cog) / p["Kt"]
        y[4] = i0
        for f, s in zip(self.dyn, self.slices):
            y[s] = f.initial_states(c)
        return y, i0
