"""`hysteresis`: a Dahl hysteresis (forms/dahl.py) in the flexspline, loop
half-height H = 0.3-0.8 N.m. Harmonic drive torsion curves show hysteresis
loss of the order of an arcminute at rated torque (Tuttle & Seering 1996;
Taghirad & Belanger 1998; the catalogue's lost motion, ~1 arcmin for size 17),
i.e. ~1.5 N.m of loop width at K1 = 1e4 N.m/rad: the range is below that."""
from __future__ import annotations

from ..forms.dahl import Dahl
from .base import Effect


class Hysteresis(Effect):
    id = "hysteresis"
    parameters = ("hys_H", "hys_sigma", "bw_A")

    def draw(self, rng):
        return dict(Dahl(rng).params)

    def apply(self, truth, user, forms, sizes):
        forms.append(Dahl(None, **sizes))
