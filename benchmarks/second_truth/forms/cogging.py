"""Cogging torque of the motor: a ripple locked to the rotor angle,
A*sin(k*theta_m + phi) + 0.3*A*sin(2k*theta_m + phi2), k = lcm(slots, poles)
periods per revolution. Used by the planted `cogging` effect. Permanent-magnet
motors' cogging is commonly 1-5 % of rated torque."""
from __future__ import annotations

import math

from .base import Form


class Cogging(Form):
    name = "cogging"
    family = "planted"
    role = "motor_torque"
    ranges = {"A": (2.0e-3, 5.0e-3), "phi": (0.0, 2 * math.pi), "phi2": (0.0, 2 * math.pi)}

    def torque(self, ctx, z) -> float:
        k, A = self.params["order"], self.params["A"]
        th = ctx.theta_m
        return A * math.sin(k * th + self.params["phi"]) + 0.3 * A * math.sin(2 * k * th + self.params["phi2"])
