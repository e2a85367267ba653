"""Viscous structural damping of the flexspline: Df times the elastic torsion
rate adds to the transmitted torque (Tuttle & Seering 1996, Taghirad &
Belanger 1998 both fit a damping term to the flexspline's torsion). The user's
model carries Df too (its default 0): this is a control's form."""
from __future__ import annotations

from .base import Form


class StructuralDamping(Form):
    name = "structural_damping"
    family = "transmission_loss"
    role = "transmission"
    ranges = {"Df": (1.0, 10.0)}  # N.m.s/rad

    def torque(self, ctx, z) -> float:
        return self.params["Df"] * ctx.xdot
