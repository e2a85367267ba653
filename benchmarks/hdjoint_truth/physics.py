"""The truth joint's laws, written from Yu et al. 2018 eq. (2)-(8) with the
contract's signs, plus the effects beyond the paper in forms of their own
(LuGre or tanh friction with any smoothing, Bouc-Wen or torque-domain Dahl
hysteresis, a dead zone, an exponential warm-up of Kt or of friction).

Scalar functions on floats: they run inside the integrator's loop, where
numpy's per-call overhead would cost more than the arithmetic."""
from __future__ import annotations

import math
from dataclasses import dataclass, field


@dataclass
class Form:
    """How the truth is built, beyond its parameter values."""
    friction: str = "tanh"          # "tanh": Fc*tanh(w/omega_fc); "lugre": bristle model
    omega_fc: float = 1.0           # rad/s, Coulomb smoothing of the tanh law
    stribeck: str = "gauss"         # "gauss": exp(-(w/ws)^2); "exp": exp(-|w/ws|)
    lugre_sigma0: float = 500.0     # N.m/rad, bristle stiffness
    lugre_sigma1: float = 0.15      # N.m.s/rad, bristle damping (about critical on the rotor)
    hysteresis: str = "none"        # "none", "bouc_wen" (in torsion) or "dahl_torque" (in torque)
    thermal: str = "none"           # "none", "kt" (Kt warms) or "friction" (friction warms)
    link_omega_fc: float = 0.01     # rad/s of the link, smoothing of the link friction
    integrator: str = "semi_implicit"  # "semi_implicit" (linearly implicit Euler) or "heun"
    substeps: int = 5               # integration steps per controller sample
    extra_kinematic: list = field(default_factory=list)  # [(angle "m"|"l", order, a, b), ...]
    # Outside the diagnosis' named library (for the open-library fallback):
    friction_ripple: tuple = ()     # (order, r): friction level times 1 + r*cos(order*theta_m)
    kinematic_torque: tuple = ()    # (order, c): theta_err += c*tau_f*cos(order*theta_m), rad per N.m
    friction_load: float = 0.0      # Coulomb level rises by this times the transmitted torque |tau_f|/N


def kinematic_terms(p: dict, form: Form) -> list[tuple[bool, float, float, float]]:
    """Eq. (7) with theta_w = theta_m as (on_motor_angle, order, a, b) terms,
    plus the truth's extra harmonics (computed once: the loop sums them)."""
    terms = [(False, p["omega_l"], p["al1"], p["bl1"]), (True, p["omega_w"], p["aw1"], p["bw1"]),
             (True, 2.0 * p["omega_w"], p["aw2"], p["bw2"])]
    terms += [(angle == "m", order, a, b) for angle, order, a, b in form.extra_kinematic]
    return [term for term in terms if term[2] or term[3]]


def kinematic_sum(a0: float, terms, theta_m: float, theta_l: float) -> float:
    err = a0
    for on_motor, order, a, b in terms:
        x = order * (theta_m if on_motor else theta_l)
        err += a * math.cos(x) + b * math.sin(x)
    return err


def kinematic_error(p: dict, form: Form, theta_m: float, theta_l: float) -> float:
    """theta_err of eq. (7), plus the truth's extra harmonics."""
    return kinematic_sum(p["a0"], kinematic_terms(p, form), theta_m, theta_l)


def wave_generator_torsion(p: dict, tau_w: float) -> float:
    """Eq. (4)'s wave generator term, reflected to the link side (rad)."""
    kw, cw, n = p["Kw"], p["Cw"], p["N"]
    if kw >= 1e8:
        return 0.0
    if cw <= 0.0:
        return tau_w / (n * kw)
    return math.copysign(1.0 - math.exp(-cw * abs(tau_w)), tau_w) / (cw * n * kw)


def dead_zone(x: float, width: float) -> float:
    """Lost motion: no elastic torsion within +-width/2."""
    half = 0.5 * width
    return x - half if x > half else (x + half if x < -half else 0.0)


def flexspline_torque(p: dict, dtheta_f: float) -> float:
    """Eq. (8): tau_f = tan(Cf*Kf*dtheta_f)/Cf (linear when Cf = 0)."""
    cf, kf = p["Cf"], p["Kf"]
    if cf <= 0.0:
        return kf * dtheta_f
    arg = max(-1.5, min(1.5, cf * kf * dtheta_f))  # tan's pole is beyond any torque the joint carries
    return math.tan(arg) / cf


def elastic_torsion(p: dict, form: Form, theta_m: float, theta_l: float, tau_w: float) -> float:
    """Eq. (3)/(4)/(6): the flexspline's elastic torsion, before any lost motion."""
    dtheta = theta_m / p["N"] - theta_l
    return dtheta - wave_generator_torsion(p, tau_w) - kinematic_error(p, form, theta_m, theta_l)


def thermal_factor(p: dict, t: float) -> float:
    """1 + gain*(1 - exp(-t/tc)): a warm-up that starts at the recording's start."""
    gain = p.get("warmup_gain", 0.0)
    return 1.0 + gain * (1.0 - math.exp(-t / p.get("warmup_tc", 20.0))) if gain else 1.0


def stribeck_shape(form: Form, omega: float, omega_s: float) -> float:
    x = omega / omega_s
    return math.exp(-x * x) if form.stribeck == "gauss" else math.exp(-abs(x))


def friction_level(p: dict, form: Form, omega: float, t: float, theta_m: float = 0.0, tau_f: float = 0.0) -> float:
    """Coulomb plus Stribeck level g(omega) > 0, with the warm-up when friction warms,
    the position ripple and the load's share (of the transmitted torque tau_f)
    when the form has them."""
    g = p["Fc"] + p.get("Fs", 0.0) * stribeck_shape(form, omega, p.get("omega_s", 10.0))
    if form.friction_load:
        g += form.friction_load * abs(tau_f) / p["N"]
    if form.friction_ripple:
        order, r = form.friction_ripple
        g *= 1.0 + r * math.cos(order * theta_m)
    return g * thermal_factor(p, t) if form.thermal == "friction" else g


def cogging(p: dict, theta_m: float) -> float:
    x = p.get("cog_order", 6.0) * theta_m
    return p.get("cog_a", 0.0) * math.cos(x) + p.get("cog_b", 0.0) * math.sin(x)


def motor_torque_constant(p: dict, form: Form, t: float) -> float:
    return p["Kt"] * thermal_factor(p, t) if form.thermal == "kt" else p["Kt"]


def link_load(p: dict, form: Form, theta_l: float, omega_l: float) -> float:
    """What the link's motion costs besides inertia: damping, gravity, link friction."""
    return (p["Bl"] * omega_l + p["mgl"] * math.sin(theta_l)
            + p.get("Fl", 0.0) * math.tanh(omega_l / form.link_omega_fc))
