"""Motor cogging: a torque ripple periodic in the motor angle, at an order the order search finds."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import Effect, TruthDraw


class Cogging(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        z = draw.scaled
        draw.truth.update(cog_order=float(draw.rng.choice([4.0, 6.0, 8.0])), cog_a=1.2e-3 * z(), cog_b=0.8e-3 * z())


EFFECT = Cogging(
    "cogging", "motor", (),  # the order comes from the order search
    "motor cogging / torque ripple periodic in the motor angle",
    "cog_a*cos(cog_order*theta_m) + cog_b*sin(cog_order*theta_m) added to the motor torque",
    switched_by=("cog_a", "cog_b"), needs=("angle",), lookalikes=("kinematic_error",),
    revealed_by="a slow motor sweep with the link blocked or unloaded (ripple in the current, not the torsion)",
    resizes=("cog_a", "cog_b"), order_angles=("theta_m",), slots=(("cog", "theta_m"),), rank=4)
