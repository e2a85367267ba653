"""Flexspline stiffening with torque, eq. (5)."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import TABLE_JOINT, Effect, Size, TruthDraw


class StiffnessNonlinearity(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        draw.truth["Cf"] = 0.0645 * draw.scaled()


EFFECT = StiffnessNonlinearity(
    "stiffness_nonlinearity", "transmission", ("Cf",),
    "flexspline stiffening with torque (the catalogue's K1 -> K3)", "atan law of eq. (5) with Cf",
    switched_by=("Cf",), starts=({"Cf": 0.03}, {"Cf": 0.08}, {"Cf": 0.2}), needs=("torque",),
    lookalikes=("wave_generator_compliance",),
    revealed_by="a wider torque range at slow motion (slow ramps of the load up to the rated torque)",
    resizes=("Cf", "Kf"), size=Size("Cf", source=TABLE_JOINT + " (K1 -> K3 at T2, catalogue)"), rank=4)
