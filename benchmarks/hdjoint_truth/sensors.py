"""The truth's measurement chain: what a drive logs of the joint's motion.

Encoders: an interpolation error periodic in the line pitch, then a
quantiser that floors (incremental counters) or rounds (absolute encoders
that report the nearest count). The current: the actual current through a
sensor with gain error, offset, a first-order lag or a pure delay, white
plus coloured (first-order autoregressive) noise. Sampling: each sample is
taken up to `jitter` seconds after its nominal instant."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


@dataclass
class Encoder:
    counts: float                # counts per revolution (0: not quantised)
    rounding: str = "floor"      # "floor" or "round"
    interpolation: float = 0.0   # amplitude of the interpolation error, in counts

    def read(self, theta: np.ndarray) -> np.ndarray:
        if self.counts <= 0:
            return np.asarray(theta, float)
        if self.rounding not in ("floor", "round"):
            raise ValueError(f"encoder rounding must be 'floor' or 'round', not {self.rounding!r}")
        step = 2.0 * math.pi / self.counts
        lines = self.counts / 4.0  # quadrature: four counts per line, the error repeats every line
        seen = theta + self.interpolation * step * np.sin(lines * theta)
        return step * (np.floor(seen / step) if self.rounding == "floor" else np.round(seen / step))


@dataclass
class CurrentSensor:
    gain_error: float = 0.0      # relative
    offset: float = 0.0          # A
    white: float = 0.01          # A, std of white noise
    coloured: float = 0.0        # A, std of the coloured (AR(1)) noise
    colour_time: float = 0.02    # s, its correlation time
    lag: float = 0.0             # s, first-order lag of the sensor
    delay: float = 0.0           # s, pure delay (whole samples)

    def read(self, current: np.ndarray, dt: float, rng: np.random.Generator) -> np.ndarray:
        x = np.asarray(current, float)
        if self.delay > 0:
            k = int(round(self.delay / dt))
            x = np.concatenate([np.full(k, x[0]), x[:-k]]) if k else x
        if self.lag > 0:
            x = first_order_lag(x, dt, self.lag)
        noise = rng.normal(0.0, self.white, len(x))
        if self.coloured > 0:
            noise += ar1(len(x), self.coloured, math.exp(-dt / self.colour_time), rng)
        return (1.0 + self.gain_error) * x + self.offset + noise


def first_order_lag(x: np.ndarray, dt: float, tau: float) -> np.ndarray:
    from scipy.signal import lfilter
    a = 1.0 - math.exp(-dt / tau)
    y, _ = lfilter([a], [1.0, a - 1.0], x, zi=[(1.0 - a) * x[0]])
    return y


def ar1(n: int, std: float, rho: float, rng: np.random.Generator) -> np.ndarray:
    """Stationary AR(1) noise of standard deviation `std` and lag-one correlation `rho`."""
    from scipy.signal import lfilter
    e = rng.normal(0.0, std * math.sqrt(1.0 - rho * rho), n)
    y, _ = lfilter([1.0], [1.0, -rho], e, zi=[rng.normal(0.0, std) * rho])
    return y


def sample_offsets(n: int, jitter: float, rng: np.random.Generator) -> np.ndarray:
    """How late each sample is taken after its nominal instant (uniform in [0, jitter])."""
    if jitter < 0:
        raise ValueError(f"sampling jitter must be >= 0 s, not {jitter}")
    return rng.uniform(0.0, jitter, n) if jitter > 0 else np.zeros(n)
