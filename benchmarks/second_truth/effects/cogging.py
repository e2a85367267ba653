"""`cogging`: the motor's cogging ripple (forms/cogging.py), 2-5 mN.m at the
motor (1-4 % of a small motor's ~0.13 N.m rated torque), at lcm(slots, poles)
periods per revolution: 6, 12, 18 or 24, with a second harmonic."""
from __future__ import annotations

from ..forms.cogging import Cogging
from .base import Effect

ORDERS = (6.0, 12.0, 18.0, 24.0)


class CoggingEffect(Effect):
    id = "cogging"
    parameters = ("cog_a", "cog_b", "cog_order")

    def draw(self, rng):
        sizes = dict(Cogging(rng).params)
        sizes["order"] = float(rng.choice(ORDERS))
        return sizes

    def apply(self, truth, user, forms, sizes):
        forms.append(Cogging(None, **sizes))
