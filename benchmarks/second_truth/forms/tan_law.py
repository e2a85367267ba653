"""The flexspline's stiffening law of the paper (Yu et al. 2018 eq. (5)/(8)):
tau = tan(Cf*Kf*x)/Cf. Beyond |Cf*Kf*x| = 1.35 (about 4.5x the zero-torque
stiffness, far past any torque these joints carry) it continues linearly so a
solver's trial step cannot reach the tangent's pole."""
from __future__ import annotations

import math

from .base import Form

A_MAX = 1.35


class TanLaw(Form):
    name = "tan_law"
    family = "stiffness_law"
    role = "stiffness"

    def bind(self, p):
        self.Kf, self.Cf = p["Kf"], p["Cf"]

    def elastic(self, x: float) -> tuple[float, float]:
        Kf, Cf = self.Kf, self.Cf
        if Cf <= 0.0:
            return Kf * x, Kf
        a = Cf * Kf * x
        if abs(a) <= A_MAX:
            c = math.cos(a)
            return math.tan(a) / Cf, Kf / (c * c)
        am = math.copysign(A_MAX, a)
        c = math.cos(am)
        k = Kf / (c * c)
        return math.tan(am) / Cf + k * (x - am / (Cf * Kf)), k

    def inverse(self, tau: float) -> float:
        Kf, Cf = self.Kf, self.Cf
        if Cf <= 0.0:
            return tau / Kf
        return math.atan(Cf * tau) / (Cf * Kf)
