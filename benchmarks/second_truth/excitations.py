"""Link references a test engineer would run: point-to-point moves with dwells
and reversals, constant-speed sweeps back and forth, and a chirp. Each returns
(r, rdot, rddot) on the sample grid; derivatives by np.gradient of a smooth r."""
from __future__ import annotations

import numpy as np

EXCITATIONS = ("dwell_reversals", "constant_speed", "chirp")


def _smoothstep(s):
    s = np.clip(s, 0.0, 1.0)
    return s ** 3 * (10 - 15 * s + 6 * s * s)  # minimum-jerk profile


def dwell_reversals(t, rng):
    """Minimum-jerk moves of 0.8-1.5 s between targets in +-1 rad, dwelling 0.3-1 s."""
    r = np.zeros_like(t)
    t0, pos = 0.5, 0.0
    r[:] = pos
    while t0 < t[-1]:
        target = float(rng.uniform(0.3, 1.0)) * (-1.0 if pos > 0 else 1.0)
        T = float(rng.uniform(0.8, 1.5))
        m = t >= t0
        r[m] = pos + (target - pos) * _smoothstep((t[m] - t0) / T)
        pos, t0 = target, t0 + T + float(rng.uniform(0.3, 1.0))
    return r


def constant_speed(t, rng):
    """Legs across +-0.9 rad at 0.25-1 rad/s, 0.2 s smooth ramps, 0.3 s dwells."""
    dt = t[1] - t[0]
    v = np.zeros_like(t)
    levels = rng.permutation([0.25, 0.5, 1.0])
    t0, sign, j = 0.5, 1.0, 0
    D, Tr = 1.8, 0.2
    while t0 < t[-1]:
        vj = levels[j % 3] * sign
        T = D / abs(vj) + Tr
        s = (t - t0)
        prof = _smoothstep(s / Tr) - _smoothstep((s - (T - Tr)) / Tr)
        v += vj * prof * ((s >= 0) & (s <= T))
        t0, sign, j = t0 + T + 0.3, -sign, j + 1
    r = np.cumsum(v) * dt
    return r - 0.9 * (np.max(r) > 0)  # start at -0.9, sweep up first


def chirp(t, rng):
    """Log chirp 0.1 -> 2.5 Hz, amplitude smoothly limited to 6 rad/s^2, around a drawn offset."""
    f0, f1 = 0.1, 2.5
    T = t[-1] if t[-1] > 0 else 1.0
    k = np.log(f1 / f0) / T
    f = f0 * np.exp(k * t)
    phase = 2 * np.pi * f0 * (np.exp(k * t) - 1) / k
    # a smooth min of 0.8 rad and 6 rad/s^2 / (2*pi*f)^2: a hard min's corner would put a spike
    # into the acceleration feed-forward (and a current spike into the recording)
    amp = _smoothstep(t / 0.5) / np.sqrt(0.8 ** -2 + ((2 * np.pi * f) ** 2 / 6.0) ** 2)
    return float(rng.uniform(-0.3, 0.3)) * _smoothstep(t / 0.5) + amp * np.sin(phase)


def reference(name: str, duration: float, Ts: float, rng):
    t = np.arange(int(round(duration / Ts)) + 1) * Ts
    r = {"dwell_reversals": dwell_reversals, "constant_speed": constant_speed, "chirp": chirp}[name](t, rng)
    rd = np.gradient(r, Ts, edge_order=2)
    rdd = np.gradient(rd, Ts, edge_order=2)
    return r, rd, rdd
