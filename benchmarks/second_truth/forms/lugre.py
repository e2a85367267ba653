"""LuGre motor friction (Canudas de Wit, Olsson, Astrom, Lischinsky 1995,
IEEE TAC 40(3)): bristle deflection z, dz/dt = w - sigma0*|w|*z/g(w),
F = sigma0*z + sigma1*dz/dt, g the joint's Stribeck curve (coulomb.stribeck);
the viscous part is the joint's Bm. In steady sliding F = g(w); near rest it
gives presliding (a spring of stiffness sigma0) and hysteresis loops.
sigma0 is drawn so the presliding displacement Fc/sigma0 is 0.15-1.5 mrad
at the motor; sigma1 near the bristles' critical damping."""
from __future__ import annotations

import math

from .base import Form
from .coulomb import stribeck


class LuGre(Form):
    name = "lugre"
    family = "motor_friction"
    role = "motor_friction"
    ranges = {"presliding": (1.5e-4, 1.5e-3), "zeta": (0.3, 1.0)}
    LOG = frozenset({"presliding"})
    n_states = 1
    state_atol = (1e-9,)

    def bind(self, p):
        self.p = p
        self.sigma0 = p["Fc"] / self.params["presliding"]
        self.sigma1 = 2.0 * self.params["zeta"] * math.sqrt(self.sigma0 * p["Jm"])

    def _zdot(self, w, z):
        return w - self.sigma0 * abs(w) * z / stribeck(self.p, w)

    def rates(self, ctx, z):
        return [self._zdot(ctx.omega_m, z[0])]

    def torque(self, ctx, z) -> float:
        return self.sigma0 * z[0] + self.sigma1 * self._zdot(ctx.omega_m, z[0])
