"""A time delay between the current measurement and the encoders."""
from __future__ import annotations

from hdjoint.diagnosis.effects.base import Effect, Size, TruthDraw


class TimeDelay(Effect):
    def plant_in_truth(self, draw: TruthDraw) -> None:
        if draw.rng.random() < 0.5:
            draw.sensor.lag = 2.5e-3 * draw.scaled()
        else:
            draw.sensor.delay = 2e-3 * draw.size


EFFECT = TimeDelay(
    "time_delay", "motor", ("i_delay",),
    "a time delay between the current measurement and the encoders", "current realigned by i_delay",
    switched_by=("i_delay",), starts=({"i_delay": 1e-3}, {"i_delay": 3e-3}, {"i_delay": 8e-3}),
    needs=("current_dynamics",), lookalikes=("viscous_friction",),
    revealed_by="fast current steps at standstill", resizes=("i_delay",),
    size=Size("i_delay", reference=(("i_delay", 1e-3),)), rank=5)
