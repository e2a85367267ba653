"""Motor friction, static law: Coulomb with a Stribeck rise, smoothed through
zero speed, g(w)*tanh(w/w_c), g(w) = Fc + Fs*exp(-(w/w_s)^2) (Armstrong-Helouvry's
steady-state curve; Fs = 0 unless the stribeck effect is planted). The
smoothing speed w_c is drawn (a real rotor's is not the user's 1 rad/s)."""
from __future__ import annotations

import math

from .base import Form


def stribeck(p: dict, w: float) -> float:
    """The joint's steady-state friction level g(w) > 0 at motor speed w."""
    ws = p.get("omega_s", 1.0)
    return p["Fc"] + p.get("Fs", 0.0) * math.exp(-(w / ws) ** 2)


class Coulomb(Form):
    name = "coulomb"
    family = "motor_friction"
    role = "motor_friction"
    ranges = {"omega_c": (0.1, 1.0)}  # rad/s at the motor
    LOG = frozenset({"omega_c"})

    def bind(self, p):
        self.p = p

    def torque(self, ctx, z) -> float:
        w = ctx.omega_m
        return stribeck(self.p, w) * math.tanh(w / self.params["omega_c"])
