"""Coulomb friction of the motor and wave generator."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import TABLE_JOINT, Effect, Size, TruthDraw


class CoulombFriction(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        draw.truth["Fc"] = 0.015 * draw.scaled()


EFFECT = CoulombFriction(
    "coulomb_friction", "motor", ("Fc",),
    "Coulomb friction of motor and wave generator", "tau_fm = Fc*tanh(omega_m/omega_fc)",
    switched_by=("Fc",), starts=({"Fc": 0.005}, {"Fc": 0.02}), needs=("speed_reversals",),
    lookalikes=("hysteresis", "stribeck_friction", "wave_generator_load"),
    revealed_by="constant-speed runs in both directions at several speeds",
    shape=("omega_fc",), resizes=("Fc", "omega_fc"), in_friction_law=True, size=Size("Fc", source=TABLE_JOINT),
    rank=1)
