"""Kinematic error beyond eq. (7): gear-meshing transmission error at further
orders of the motor or link angle, in four order slots the order search fills."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import Effect, Size, TruthDraw

# The eq. (7) kinematic-error terms the nominal model carries (link order 1, wave generator orders 1 and 2).
KINEMATIC_EQ7 = ("al1", "bl1", "aw1", "bw1", "aw2", "bw2")


class KinematicError(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        z = draw.scaled
        if draw.rng.random() < 0.5:
            draw.form.extra_kinematic += [("m", 3.0, 6e-6 * z(), -4e-6 * z()), ("m", 5.0, 4e-6 * z(), 0.0)]
        else:
            draw.form.extra_kinematic += [("l", 2.0, 3e-5 * z(), 2e-5 * z()), ("m", 4.0, 5e-6 * z(), 0.0)]


EFFECT = KinematicError(
    "kinematic_error", "transmission", (),  # slots are chosen by the order search
    "kinematic error (gear-meshing transmission error) at orders of the motor or link angle beyond eq. (7)",
    "extra Fourier terms of theta_m and theta_l in theta_err (ke_m1/ke_m2/ke_l1/ke_l2)",
    needs=("angle",), lookalikes=("cogging",),
    revealed_by="a slow sweep of the motor over many revolutions at constant, low load",
    resizes=KINEMATIC_EQ7, order_angles=("theta_m", "theta_l"),
    slots=(("ke_m1", "theta_m"), ("ke_m2", "theta_m"), ("ke_l1", "theta_l"), ("ke_l2", "theta_l")),
    seen_on_torsion=True,
    # Planted at the lowest link order beyond eq. (7), a ripple of 1 arcmin peak to peak.
    size=Size("ke_l1_a", reference=(("ke_l1_order", 2.0), ("ke_l1_a", 1.45e-4)),
              source="a ripple of 1 arcmin peak to peak, the transmission accuracy of Harmonic Drive gears (catalogue)"),
    rank=1)
