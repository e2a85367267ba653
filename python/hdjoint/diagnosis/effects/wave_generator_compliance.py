"""Wave generator compliance, eq. (4): the bearing and plug twist with the motor-side torque."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import TABLE_JOINT, Effect, Size, TruthDraw


class WaveGeneratorCompliance(Effect):
    def is_on(self, p: dict) -> bool:
        return p.get("Kw", 1e9) < 1e8  # the table's "off" is a rigid wave generator (Kw = 1e9)

    def plant_in_truth(self, draw: TruthDraw) -> None:
        draw.truth.update(Kw=40.0 * draw.jitter() / draw.size, Cw=10.0 * draw.jitter())


EFFECT = WaveGeneratorCompliance(
    "wave_generator_compliance", "transmission", ("Kw", "Cw"),
    "wave generator (bearing and plug) compliance, eq. (4)", "wg(tau) with Kw, Cw",
    starts=({"Kw": 3.0, "Cw": 0.0}, {"Kw": 10.0, "Cw": 10.0}, {"Kw": 30.0, "Cw": 30.0}),
    needs=("torque",), lookalikes=("stiffness_nonlinearity", "backlash"),
    revealed_by="fast motor accelerations at low load (the wave generator twists with the motor-side "
                "torque, the flexspline with the link torque)",
    resizes=("Kw", "Cw"), size=Size("Kw", -1.0, source=TABLE_JOINT), rank=2)
