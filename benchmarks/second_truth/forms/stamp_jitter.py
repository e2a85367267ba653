"""A jittery time column: the readings are taken on the tick, but the time
stamp written is t_k + e_k, e_k uniform in +-h (h 20-200 us < Ts/2, so the
column stays strictly increasing), as a logger that stamps with its own clock
on receipt does."""
from __future__ import annotations

import numpy as np

from .base import Form


class StampJitter(Form):
    name = "stamp_jitter"
    family = "timing"
    role = "timing"
    ranges = {"h": (2e-5, 2e-4)}

    def apply(self, rec: dict, rng) -> None:
        rec["time"] = rec["time"] + rng.uniform(-self.params["h"], self.params["h"], len(rec["time"]))
