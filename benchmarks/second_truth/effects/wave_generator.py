"""`wave_generator_compliance`: the wave generator bearing's compliance of
contract eq. (4), Kw = 5-20 N.m/rad, Cw = 5-20 1/(N.m) (the size Yu et al.
2018 identify), loaded by the transmitted torque's share tau_f/N. The user
types a rigid wave generator (Kw = 1e9), as its catalogue gives no figure."""
from __future__ import annotations

from .base import Effect


class WaveGenerator(Effect):
    id = "wave_generator_compliance"
    parameters = ("Kw", "Cw")

    def draw(self, rng):
        return {"Kw": float(rng.uniform(5.0, 20.0)), "Cw": float(rng.uniform(5.0, 20.0))}

    def apply(self, truth, user, forms, sizes):
        truth["Kw"], truth["Cw"] = sizes["Kw"], sizes["Cw"]
