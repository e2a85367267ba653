"""`gravity_load`: the user models the joint as if it moved horizontally
(mgl = 0) while the link carries 3-8 N.m of gravity torque (the truth's mgl)."""
from __future__ import annotations

from .base import Effect


class Gravity(Effect):
    id = "gravity_load"
    expected_kind = ("added", "resized")
    parameters = ("mgl",)

    def draw(self, rng):
        return {}

    def apply(self, truth, user, forms, sizes):
        sizes["mgl_truth"] = truth["mgl"]
        user["mgl"] = 0.0
