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


class _UniformFilter:
    """Cubic Savitzky-Golay filtering of one contiguous piece on a uniform
    grid (irregular time stamps are interpolated onto the median step and back)."""

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


class _Filter:
    """The same filter over each window of a recording on its own: a window
    sampled out of a long recording must not be smoothed across the jump to
    the next one."""

    def __init__(self, t: np.ndarray, window_s: float, starts: np.ndarray):
        self.bounds = list(zip(starts, list(starts[1:]) + [len(t)]))
        self.pieces = [_UniformFilter(t[a:b], window_s) for a, b in self.bounds]
        self.window = self.pieces[0].window

    def __call__(self, x: np.ndarray, deriv: int = 0) -> np.ndarray:
        if len(self.pieces) == 1:
            return self.pieces[0](x, deriv)
        return np.concatenate([f(x[a:b], deriv) for f, (a, b) in zip(self.pieces, self.bounds)])


def kinematics(rec: Recording, window_s: float = 0.025, starts: np.ndarray | None = None) -> Kinematics:
    """Speeds and accelerations of motor and link from the encoder angles.

    A 25 ms cubic Savitzky-Golay window turns a 4096-count encoder into a
    usable speed at 1 kHz while passing the joint's motion (a few Hz).
    `starts`: first sample of each contiguous window (default: one window)."""
    f = _Filter(rec.time, window_s, np.array([0]) if starts is None else np.asarray(starts))
    return Kinematics(f(rec.theta_m, 1), f(rec.theta_m, 2), f(rec.theta_l, 1), f(rec.theta_l, 2), f)


def folds(n: int, count: int = 10) -> np.ndarray:
    """Contiguous blocks labelled 0..count-1 in turn: even labels fit, odd
    labels are held out, so both halves cover the whole run and every regime."""
    return (np.arange(n) * count // max(n, 1)).astype(int)


def sample_windows(rec: Recording, analysed_seconds: float, count: int) -> tuple[Recording, np.ndarray]:
    """A long recording's analysed part: `count` contiguous windows spread
    evenly over the whole run, `analysed_seconds` in all, and the index where
    each window starts in the result. A recording no longer than that is
    returned whole (one window).

    Why windows and not decimation: the encoder speeds need the full sample
    rate, and hysteresis and delays need contiguous history; spreading the
    windows over the run keeps slow changes (warm-up over an hour) visible."""
    if rec.duration <= analysed_seconds:
        return rec, np.array([0])
    length = analysed_seconds / count
    first = np.linspace(rec.time[0], rec.time[-1] - length, count)
    lo = np.searchsorted(rec.time, first)
    hi = np.searchsorted(rec.time, first + length)
    keep = np.concatenate([np.arange(a, b) for a, b in zip(lo, hi)])
    starts = np.concatenate([[0], np.cumsum(hi - lo)[:-1]])

    def take(a):
        return None if a is None else a[keep]

    sampled = Recording(time=rec.time[keep], i_m=rec.i_m[keep], theta_m=rec.theta_m[keep],
                        theta_l=rec.theta_l[keep], tau_sensor=take(rec.tau_sensor),
                        extra={k: v[keep] for k, v in rec.extra.items()}, path=rec.path)
    return sampled, starts


def window_labels(n: int, starts: np.ndarray) -> np.ndarray:
    """Each sample's window number."""
    labels = np.zeros(n, int)
    labels[np.asarray(starts[1:], int)] = 1
    return np.cumsum(labels)
