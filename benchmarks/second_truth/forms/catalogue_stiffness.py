"""Harmonic Drive catalogue stiffness: three straight segments K1 (|tau| < T1),
K2 (T1..T2), K3 (beyond T2), the way the SHD/CSD catalogues state torsional
stiffness. Size 17, ratio 100 figures as quoted in src/hdjoint/parameter_table.def
(K1 = 1.0e4, K3 = 1.6e4 N.m/rad, T1 = 3.9, T2 = 12 N.m); K2 = 1.3e4 is the
midpoint (an assumption of this file). The slopes are scaled so that K1 equals
the truth's Kf. A model form the user's atan/tan law only approximates:
its family is held out of tuning."""
from __future__ import annotations

import math

from .base import Form

T1, T2 = 3.9, 12.0
R2, R3 = 1.3, 1.6  # K2/K1, K3/K1


class CatalogueStiffness(Form):
    name = "catalogue_stiffness"
    family = "stiffness_law"
    role = "stiffness"

    def bind(self, p):
        self.K1 = p["Kf"]
        self.K2, self.K3 = R2 * self.K1, R3 * self.K1
        self.x1 = T1 / self.K1
        self.x2 = self.x1 + (T2 - T1) / self.K2

    def elastic(self, x: float) -> tuple[float, float]:
        ax = abs(x)
        if ax <= self.x1:
            t, k = self.K1 * ax, self.K1
        elif ax <= self.x2:
            t, k = T1 + self.K2 * (ax - self.x1), self.K2
        else:
            t, k = T2 + self.K3 * (ax - self.x2), self.K3
        return math.copysign(t, x), k

    def inverse(self, tau: float) -> float:
        a = abs(tau)
        if a <= T1:
            x = a / self.K1
        elif a <= T2:
            x = self.x1 + (a - T1) / self.K2
        else:
            x = self.x2 + (a - T2) / self.K3
        return math.copysign(x, tau)
