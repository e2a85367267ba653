"""`stribeck_friction`: breakaway friction above the running level: a rise
Fs = 0.5-1.0 Fc decaying over w_s = 3-15 rad/s at the motor (Armstrong-Helouvry
1991 report static friction exceeding Coulomb by tens of percent to twofold)."""
from __future__ import annotations

from .base import Effect


class Stribeck(Effect):
    id = "stribeck_friction"
    parameters = ("Fs", "omega_s")

    def draw(self, rng):
        return {"Fs_ratio": float(rng.uniform(0.5, 1.0)), "omega_s": float(rng.uniform(3.0, 15.0))}

    def apply(self, truth, user, forms, sizes):
        truth["Fs"] = sizes["Fs_ratio"] * truth["Fc"]
        truth["omega_s"] = sizes["omega_s"]
