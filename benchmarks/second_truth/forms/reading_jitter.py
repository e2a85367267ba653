"""Reading-time jitter: the logger reads both encoders at t_k + j_k (j_k
Gaussian, sigma 5-50 us, clipped at +-0.4 Ts) but stamps the row t_k, as a
non-real-time logging thread does. The current keeps its own sensor's timing."""
from __future__ import annotations

import numpy as np

from .base import Form


class ReadingJitter(Form):
    name = "reading_jitter"
    family = "timing"
    role = "timing"
    ranges = {"sigma": (5e-6, 5e-5)}

    def read_times(self, ticks: np.ndarray, rng) -> np.ndarray:
        Ts = ticks[1] - ticks[0]
        j = np.clip(rng.normal(0.0, self.params["sigma"], len(ticks)), -0.4 * Ts, 0.4 * Ts)
        return ticks + j
