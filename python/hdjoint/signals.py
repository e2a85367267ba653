"""Derived signals for residual analysis: speeds and accelerations from
quantised encoders (Savitzky-Golay on a uniform grid, so irregular sampling
is handled), and contiguous fold labels."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import savgol_filter

from .recording import Recording


@dataclass
class Kinematics:
    """Smoothed motion of both sides, on the recording's own time stamps, and
    the same smoothing for any other signal (`smooth`): an equation mixing
    differentiated encoders with raw signals must see all of them through
    the same filter, or the filter's own lag and attenuation look like physics."""
    omega_m: np.ndarray
    alpha_m: np.ndarray
    omega_l: np.ndarray
    alpha_l: np.ndarray
    smooth: "callable"


class _Filter:
    """Cubic Savitzky-Golay filtering on a uniform grid (irregular time
    stamps are interpolated onto the median step and back)."""

    def __init__(self, t: np.ndarray, window_s: float):
        self.t = t
        self.step = float(np.median(np.diff(t)))
        self.uniform = np.abs(np.diff(t) - self.step).max() <= 1e-3 * self.step
        self.grid = t if self.uniform else np.arange(t[0], t[-1] + self.step / 2, self.step)
        window = max(5, int(round(window_s / self.step)) | 1)  # odd, at least 5 samples
        longest_odd = len(self.grid) if len(self.grid) % 2 else len(self.grid) - 1
        self.window = min(window, longest_odd)
        if self.window < 5:
            raise ValueError("the recording is too short to differentiate its encoder angles")

    def __call__(self, x: np.ndarray, deriv: int = 0) -> np.ndarray:
        xg = x if self.uniform else np.interp(self.grid, self.t, x)
        y = savgol_filter(xg, self.window, 3, deriv=deriv, delta=self.step, mode="interp")
        return y if self.uniform else np.interp(self.t, self.grid, y)


def kinematics(rec: Recording, window_s: float = 0.025) -> Kinematics:
    """Speeds and accelerations of motor and link from the encoder angles.

    A 25 ms cubic Savitzky-Golay window turns a 4096-count encoder into a
    usable speed at 1 kHz while passing the joint's motion (a few Hz)."""
    f = _Filter(rec.time, window_s)
    return Kinematics(f(rec.theta_m, 1), f(rec.theta_m, 2), f(rec.theta_l, 1), f(rec.theta_l, 2), f)


def folds(n: int, count: int = 10) -> np.ndarray:
    """Contiguous blocks labelled 0..count-1 in turn: even labels fit, odd
    labels are held out, so both halves cover the whole run and every regime."""
    return (np.arange(n) * count // max(n, 1)).astype(int)
