"""Generalized Maxwell-slip motor friction (Al-Bender, Lampaert, Swevers 2005,
IEEE TAC 50(11)): M elasto-slide elements in parallel, element i a spring k_i
that sticks until its force reaches alpha_i*s(w) and then slides, relaxing to
alpha_i*s(w) at rate C; sum alpha_i = 1, s the joint's Stribeck curve.
Presliding with non-local memory. The stick/slip switch is regularised over
the last 5 % of each element's limit so the ODE solver sees a continuous
right-hand side. Element breakaway displacements are log-spaced in a drawn
range (0.05-2 mrad at the motor); the weights are drawn."""
from __future__ import annotations

import math

from .base import Form
from .coulomb import stribeck

M = 4
DELTA = 0.05


class GMS(Form):
    name = "gms"
    family = "motor_friction"
    role = "motor_friction"
    ranges = {"d_min": (5e-5, 2e-4), "d_max": (5e-4, 2e-3), "C": (200.0, 2000.0),
              **{f"w{k}": (0.5, 1.5) for k in range(M)}}
    LOG = frozenset({"d_min", "d_max", "C"})
    n_states = M
    state_atol = (1e-9,) * M

    def bind(self, p):
        self.p = p
        w = [self.params[f"w{k}"] for k in range(M)]
        self.alpha = [x / sum(w) for x in w]
        lo, hi = math.log(self.params["d_min"]), math.log(self.params["d_max"])
        self.delta = [math.exp(lo + (hi - lo) * k / (M - 1)) for k in range(M)]

    def rates(self, ctx, z):
        w = ctx.omega_m
        s = stribeck(self.p, w)
        sg = math.tanh(w / 1e-3)
        C = self.params["C"]
        out = []
        for a, d, F in zip(self.alpha, self.delta, z):
            lim = a * s
            u = sg * F / lim
            if u <= 1.0 - DELTA:
                sig = 0.0
            elif u >= 1.0:
                sig = 1.0
            else:
                sig = ((u - 1.0 + DELTA) / DELTA) ** 2
            k = a * self.p["Fc"] / d
            out.append(k * w * (1.0 - sig) + sg * C * lim * (1.0 - u) * sig)
        return out

    def torque(self, ctx, z) -> float:
        return float(sum(z))
