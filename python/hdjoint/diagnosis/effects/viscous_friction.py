"""Viscous friction proportional to the motor speed."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import TABLE_JOINT, Effect, Size, TruthDraw


class ViscousFriction(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        draw.truth["Bm"] = 1.5e-4 * draw.scaled()


EFFECT = ViscousFriction(
    "viscous_friction", "motor", ("Bm",),
    "viscous friction proportional to motor speed", "Bm*omega_m", switched_by=("Bm",),
    starts=({"Bm": 2e-5}, {"Bm": 1e-4}), needs=("speed",), lookalikes=("time_delay",),
    revealed_by="constant high speeds (no acceleration, so no delay shows)", resizes=("Bm",),
    in_friction_law=True, size=Size("Bm", source=TABLE_JOINT), rank=3)
