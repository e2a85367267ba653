"""Dahl hysteresis of the transmission (Dahl 1968, 'A solid friction model',
Aerospace Corp. TOR-158): dz/dx = sigma*|1 - z/H*sgn(xdot)|^n * sgn(1 - z/H*sgn(xdot)),
x the flexspline's elastic torsion, z added to the transmitted torque.
The exponent n (Dahl's i; 1 in the linear Dahl model) is drawn. Used by the
planted `hysteresis` effect, not as a control's form."""
from __future__ import annotations

import math

from .base import Form


class Dahl(Form):
    name = "dahl_hysteresis"
    family = "planted"
    role = "transmission"
    ranges = {"H": (0.3, 0.8), "sigma_ratio": (1.0, 3.0), "n": (0.6, 1.5)}
    n_states = 1
    state_atol = (1e-7,)

    def bind(self, p):
        self.sigma = self.params["sigma_ratio"] * p["Kf"]

    def rates(self, ctx, z):
        xd = ctx.xdot
        H = self.params["H"]
        r = 1.0 - z[0] / H * math.copysign(1.0, xd)
        return [self.sigma * xd * math.copysign(abs(r) ** self.params["n"], r)]

    def torque(self, ctx, z) -> float:
        return z[0]
