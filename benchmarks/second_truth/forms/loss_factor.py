"""Hysteretic (structural) loss of the flexspline: a loss torque proportional
to the elastic torque, opposing the torsion rate, eta*|tau_el|*tanh(xdot/v0):
the rate-independent 'structural damping' of solids with a loss factor eta
(as Taghirad & Belanger 1998 model the harmonic drive's torsional hysteresis
by a load-proportional friction). eta drawn 0.5-1.5 %: a thin loop, well below
the planted hysteresis."""
from __future__ import annotations

import math

from .base import Form


class LossFactor(Form):
    name = "loss_factor"
    family = "transmission_loss"
    role = "transmission"
    ranges = {"eta": (0.005, 0.015), "v0": (1e-4, 1e-3)}  # 1, rad/s of torsion rate

    def torque(self, ctx, z) -> float:
        return self.params["eta"] * abs(ctx.tau_el) * math.tanh(ctx.xdot / self.params["v0"])
