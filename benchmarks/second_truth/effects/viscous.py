"""`viscous_friction`: the gear's speed-dependent running torque, Bm = 2-5e-4
N.m.s/rad at the motor (0.02-0.05 N.m at 100 rad/s, of the order of the
no-load running torque rise with speed in Harmonic Drive catalogues), where
the user types the rotor's 3e-5."""
from __future__ import annotations

from .base import Effect


class Viscous(Effect):
    id = "viscous_friction"
    expected_kind = ("added", "resized")
    parameters = ("Bm",)

    def draw(self, rng):
        return {"Bm": float(rng.uniform(2e-4, 5e-4))}

    def apply(self, truth, user, forms, sizes):
        truth["Bm"] = sizes["Bm"]
