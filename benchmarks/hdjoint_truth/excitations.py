"""Link position references for the truth's controller, each t -> (theta,
omega, alpha) in rad, rad/s, rad/s^2. Written here, not shared with
hdjoint.fmu.experiments, so the benchmark's excitations are not the ones the
diagnosis was tuned on."""
from __future__ import annotations

import math

import numpy as np


def _smoothstep(x):
    """0 -> 1 over [0, 1] with zero speed and acceleration at both ends (quintic)."""
    x = np.clip(x, 0.0, 1.0)
    return x ** 3 * (10 - 15 * x + 6 * x * x), 30 * x * x * (1 - x) ** 2, 60 * x * (1 - x) * (1 - 2 * x)


def paper(t, scale=1.0):
    """A 0.25 Hz sinusoid whose amplitude grows from 0.05 to 1.2 rad over the run (gravity torque grows)."""
    T = max(t[-1], 1.0)
    a = scale * (0.05 + 1.15 * t / T)
    da = scale * 1.15 / T
    w = 2 * math.pi * 0.25
    s, c = np.sin(w * t), np.cos(w * t)
    return a * s, a * w * c + da * s, -a * w * w * s + 2 * da * w * c


def multisine(t, scale=1.0):
    """Four incommensurate sines, 0.11-2.3 Hz, starting from rest by a 1 s fade-in."""
    theta, omega, alpha = np.zeros_like(t), np.zeros_like(t), np.zeros_like(t)
    for amp, hz, ph in ((0.5, 0.11, 0.3), (0.2, 0.37, 1.3), (0.06, 0.93, 2.1), (0.015, 2.3, 0.7)):
        w = 2 * math.pi * hz
        theta += amp * (np.sin(w * t + ph) - math.sin(ph))
        omega += amp * w * np.cos(w * t + ph)
        alpha -= amp * w * w * np.sin(w * t + ph)
    return _faded(t, scale * theta, scale * omega, scale * alpha)


def sweep(t, scale=1.0):
    """Slow point-to-point moves (3 s) with 1.5 s dwells, reversing direction every move."""
    targets = scale * np.array([0.0, 0.7, -0.4, 0.9, -0.8, 0.3, -0.6, 0.8, 0.0, -0.5, 0.6, 0.0])
    period, move = 4.5, 3.0
    k = np.minimum((t // period).astype(int), len(targets) - 2)
    s, ds, dds = _smoothstep((t - k * period) / move)
    span = targets[k + 1] - targets[k]
    return targets[k] + span * s, span * ds / move, span * dds / move ** 2


def constant_speeds(t, scale=1.0):
    """Plateaus of constant link speed (+-0.15 .. +-0.6 rad/s), reversing, joined by 0.4 s ramps."""
    speeds = scale * np.array([0.3, -0.3, 0.6, -0.6, 0.15, -0.15, 0.45, -0.45])
    hold, ramp = 3.0, 0.4
    k = (t // hold).astype(int) % len(speeds)
    target = speeds[k]
    # Speed: the plateau speed, blended from the previous one over `ramp` seconds.
    prev = speeds[(k - 1) % len(speeds)]
    s, ds, _ = _smoothstep((t - (t // hold) * hold) / ramp)
    first = t < hold
    omega = np.where(first, target * s, prev + (target - prev) * s)
    alpha = np.where(first, target * ds / ramp, (target - prev) * ds / ramp)
    theta = np.concatenate([[0.0], np.cumsum(0.5 * (omega[1:] + omega[:-1]) * np.diff(t))]) if len(t) > 1 \
        else np.zeros_like(t)
    return theta, omega, alpha


def chirp(t, scale=1.0):
    """Linear chirp 0.1 -> 3 Hz over the run, amplitude falling with frequency, faded in."""
    T = max(t[-1], 1.0)
    f0, f1 = 0.1, 3.0
    k = (f1 - f0) / T
    phase = 2 * math.pi * (f0 * t + 0.5 * k * t * t)
    f = f0 + k * t
    amp = scale * 0.4 * (f0 + 0.3) / (f + 0.3)
    w = 2 * math.pi * f
    theta = amp * np.sin(phase)
    omega = amp * w * np.cos(phase)  # the amplitude's slow change is left to the controller
    alpha = -amp * w * w * np.sin(phase)
    return _faded(t, theta, omega, alpha)


def _faded(t, theta, omega, alpha, seconds=1.0):
    f, df, ddf = _smoothstep(t / seconds)
    df, ddf = df / seconds, ddf / seconds ** 2
    return f * theta, f * omega + df * theta, f * alpha + 2 * df * omega + ddf * theta


EXCITATIONS = {"paper": paper, "multisine": multisine, "sweep": sweep, "constant_speeds": constant_speeds,
               "chirp": chirp}


def payload_steps(t):
    """External link torque (N.m): a payload changing every 5 s, each change over 50 ms."""
    levels, hold, rise = np.array([0.0, 1.2, -0.8, 2.0, 0.4, -1.5, 0.8]), 5.0, 0.05
    k = np.minimum((t // hold).astype(int), len(levels) - 1)
    s, _, _ = _smoothstep((t - k * hold) / rise)
    before = levels[np.maximum(k - 1, 0)]
    return before + (levels[k] - before) * s


def contact_pushes(t):
    """External link torque (N.m): 0.6 s raised-cosine pushes every 3.1 s, alternating 2.5 and -1.5 N.m."""
    k = np.floor(t / 3.1)
    x = (t - k * 3.1) / 0.6
    pulse = np.where(x < 1.0, 0.5 * (1.0 - np.cos(2.0 * math.pi * np.clip(x, 0.0, 1.0))), 0.0)
    return 2.5 * pulse * np.where(k % 2 == 0, 1.0, -0.6)


# What pushes on the link besides the joint, unknown to controller and estimators ("": nothing).
LOADS = {"": np.zeros_like, "payload": payload_steps, "contact": contact_pushes}


def external_load(kind: str, t: np.ndarray) -> np.ndarray:
    if kind not in LOADS:
        raise ValueError(f"unknown external load {kind!r}; known: {', '.join(k for k in LOADS if k)}")
    return LOADS[kind](np.asarray(t, float))


def reference(kind: str, t: np.ndarray, scale: float = 1.0):
    if kind not in EXCITATIONS:
        raise ValueError(f"unknown excitation {kind!r}; known: {', '.join(EXCITATIONS)}")
    return EXCITATIONS[kind](np.asarray(t, float), scale)
