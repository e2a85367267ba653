"""`backlash`: lost motion, a dead zone of total width 0.3-0.8 arcmin on the
flexspline torsion (a worn or loosely fitted output coupling). The catalogue
states about 1 arcmin of lost motion for size 17 including elastic wind-up;
a dead zone of a fraction of that is what a real joint can add."""
from __future__ import annotations

import math

from .base import Effect

ARCMIN = math.pi / (180 * 60)


class Backlash(Effect):
    id = "backlash"
    parameters = ("backlash",)

    def draw(self, rng):
        return {"backlash": float(rng.uniform(0.3, 0.8)) * ARCMIN}

    def apply(self, truth, user, forms, sizes):
        truth["backlash"] = sizes["backlash"]
