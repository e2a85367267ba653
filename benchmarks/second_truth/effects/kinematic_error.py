"""`kinematic_error`: one or two harmonics of the transmission error beyond
the paper's eq. (7) (which has link order 1 and motor orders 2 and 4): motor
orders 1, 3 or 6, link orders 2 or 3, 2-6e-5 rad each (the catalogue's
transmission accuracy is 1-1.5 arcmin = 2.9-4.4e-4 rad peak to peak)."""
from __future__ import annotations

import math

from .base import Effect

CANDIDATES = (("m", 1.0), ("m", 3.0), ("m", 6.0), ("l", 2.0), ("l", 3.0))


class KinematicError(Effect):
    id = "kinematic_error"
    parameters = ("ke_m1_a", "ke_m1_b", "ke_l1_a", "ke_l1_b")

    def draw(self, rng):
        k = int(rng.integers(1, 3))
        picks = rng.choice(len(CANDIDATES), size=k, replace=False)
        out = []
        for i in picks:
            axis, order = CANDIDATES[int(i)]
            amp, ph = float(rng.uniform(2e-5, 6e-5)), float(rng.uniform(0, 2 * math.pi))
            out.append([axis, order, amp * math.cos(ph), amp * math.sin(ph)])
        return {"harmonics": out}

    def apply(self, truth, user, forms, sizes):
        truth["harmonics"] = list(truth.get("harmonics", [])) + [tuple(h) for h in sizes["harmonics"]]
