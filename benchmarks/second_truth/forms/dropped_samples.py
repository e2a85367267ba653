"""Dropped samples: a logger that loses rows (a full buffer, a missed bus
cycle) in bursts of 1-3 samples at a rate of 0.1-0.5 % of rows. The rows are
removed; the time column keeps its true stamps, so the gaps show."""
from __future__ import annotations

import numpy as np

from .base import Form


class DroppedSamples(Form):
    name = "dropped_samples"
    family = "dropouts"
    role = "dropouts"
    ranges = {"rate": (0.001, 0.005)}

    def apply(self, rec: dict, rng) -> None:
        n = len(rec["time"])
        keep = np.ones(n, bool)
        starts = np.flatnonzero(rng.random(n) < self.params["rate"] / 2.0)
        for s in starts:
            if 10 <= s < n - 10:  # the first and last rows stay
                keep[s:s + int(rng.integers(1, 4))] = False
        rec["keep"] = rec["keep"] & keep
        rec["dropped"] = int(n - keep.sum())
