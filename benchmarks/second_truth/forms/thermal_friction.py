"""Motor friction that follows the gear's temperature: the grease's viscosity
falls as it warms, so the Coulomb+Stribeck level scales by exp(-beta*T), T the
temperature rise of a lumped thermal mass heated by the winding's copper loss
R*i^2 and the friction's own loss F*|w| (dT/dt = (P - T/Rth)/Cth).
Harmonic Drive catalogues' no-load running torque falls by about half from
0 to 40 C, i.e. beta of order 1-2 %/K. Sizes keep the rise over a 20 s
recording to a few kelvin: a few percent of friction, within its tolerance."""
from __future__ import annotations

import math

from .base import Form
from .coulomb import stribeck


class ThermalFriction(Form):
    name = "thermal_friction"
    family = "motor_friction"
    role = "motor_friction"
    ranges = {"beta": (0.01, 0.02), "R": (2.0, 4.0), "Cth": (20.0, 60.0), "Rth": (2.0, 5.0),
              "omega_c": (0.1, 1.0), "T0": (-3.0, 3.0)}
    n_states = 1
    state_atol = (1e-7,)

    def bind(self, p):
        self.p = p

    def initial_states(self, ctx):
        return [self.params["T0"]]

    def _f(self, ctx, T):
        w = ctx.omega_m
        return math.exp(-self.params["beta"] * T) * stribeck(self.p, w) * math.tanh(w / self.params["omega_c"])

    def rates(self, ctx, z):
        P = self.params["R"] * ctx.i ** 2 + abs(self._f(ctx, z[0]) * ctx.omega_m)
        return [(P - z[0] / self.params["Rth"]) / self.params["Cth"]]

    def torque(self, ctx, z) -> float:
        return self._f(ctx, z[0])
