"""`time_delay`: the drive reports its current 2-5 ms late (buffered bus
cycles), on top of the current sensor's own sub-sample lag and delay."""
from __future__ import annotations

from .base import Effect


class TimeDelay(Effect):
    id = "time_delay"
    parameters = ("i_delay",)

    def draw(self, rng):
        return {"extra_delay": float(rng.uniform(2e-3, 5e-3))}

    def apply(self, truth, user, forms, sizes):
        sensor = next(f for f in forms if f.role == "current_sensor")
        sensor.params["extra_delay"] = sizes["extra_delay"]
