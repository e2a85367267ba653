"""Motor friction that grows with the transmitted load: the gear mesh's
sliding friction is proportional to the tooth force, so the motor-side
friction level is g(w) + mu*|tau_f|/N (a harmonic drive's efficiency falls
well below 1 under load; Tuttle & Seering 1996 and Taghirad & Belanger 1998
both report load-dependent friction in harmonic drives). mu is the lost share
of the transmitted torque, drawn 3-10 %."""
from __future__ import annotations

import math

from .base import Form
from .coulomb import stribeck


class LoadFriction(Form):
    name = "load_friction"
    family = "motor_friction"
    role = "motor_friction"
    ranges = {"mu": (0.03, 0.10), "omega_c": (0.1, 1.0)}

    def bind(self, p):
        self.p = p

    def torque(self, ctx, z) -> float:
        w = ctx.omega_m
        level = stribeck(self.p, w) + self.params["mu"] * abs(ctx.tau_f) / self.p["N"]
        return level * math.tanh(w / self.params["omega_c"])
