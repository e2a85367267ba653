"""A nominal parameter far off: the user types Kf = 7000 N.m/rad (a smaller
size's K1, say) for a flexspline whose zero-torque stiffness is 2.5 times
that, 17,500 N.m/rad: 7.5 tolerances of the catalogue's +-20 % away. The
diagnosis should resize Kf with an interval holding the truth."""
from __future__ import annotations

from .base import Effect

USER_KF = 7000.0
RATIO = 2.5


class KfFarOff(Effect):
    id = "kf_far_off"
    expected_kind = ("resized",)
    parameters = ("Kf",)

    def draw(self, rng):
        return {"Kf_user": USER_KF, "Kf_truth": RATIO * USER_KF}

    def apply(self, truth, user, forms, sizes):
        user["Kf"] = sizes["Kf_user"]
        truth["Kf"] = sizes["Kf_truth"]
