"""Derived signals for residual analysis: speeds and accelerations from
quantised encoders (Gaussian derivative filters on a uniform grid, so
irregular sampling is handled), and contiguous fold labels."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.ndimage import convolve1d

from hdjoint.io.recording import Recording


@dataclass
class Kinematics:
    """Smoothed motion of both sides, on the recording's own time stamps, and
    the same smoothing for any other signal (`smooth`): an equation mixing
    differentiated encoders with raw signals must see all of them through
    the same filter, or the filter's own lag and attenuation look like physics.
    `valid` is False near the ends of each window, where the filter runs off
    the data and the derivatives are not those of the smoothed signal."""
    omega_m: np.ndarray
    alpha_m: np.ndarray
    omega_l: np.ndarray
    alpha_l: np.ndarray
    smooth: "callable"
    valid: np.ndarray


# Why Gaussian and not Savitzky-Golay: the speed and acceleration must be
# exactly the derivatives of the smoothed angle, so that Jm*alpha_m - Kt*i
# and the smoothed torque obey the same linear equation as the joint. A
# Gaussian's derivative filters are the derivatives of its smoothing filter;
# a Savitzky-Golay derivative is a different local fit, which near the
# joint's torsional mode reads as extra inertia and a current delay that the
# joint does not have.
_TRUNCATE = 4.0  # kernel half-width in standard deviations


def gaussian_kernels(sigma: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Sampled Gaussian smoothing kernel and its first and second derivatives
    (per sample), normalised so that each is exact on polynomials up to the
    cubic: scipy's gaussian_filter1d leaves the sampled second derivative 8 %
    short at 3 samples of sigma, which would read as 8 % less inertia."""
    half = int(_TRUNCATE * sigma + 0.5)
    k = np.arange(-half, half + 1, dtype=float)
    g = np.exp(-0.5 * (k / sigma) ** 2)
    g /= g.sum()
    d1 = -k / sigma ** 2 * g
    d1 /= np.sum(d1 * -k)  # convolution flips the kernel: the slope of x = n must come out 1
    d2 = (k ** 2 / sigma ** 4 - 1.0 / sigma ** 2) * g
    d2 -= g * d2.sum()  # a constant has no curvature
    d2 /= np.sum(d2 * k ** 2 / 2.0)  # the curvature of n^2/2 is 1
    return g, d1, d2


class _UniformFilter:
    """Gaussian smoothing and its derivatives over one contiguous piece on a
    uniform grid (irregular time stamps are interpolated onto the median step and back)."""

    def __init__(self, t: np.ndarray, sigma_s: float):
        self.t = t
        self.step = float(np.median(np.diff(t)))
        self.uniform = np.abs(np.diff(t) - self.step).max() <= 1e-3 * self.step
        self.grid = t if self.uniform else np.arange(t[0], t[-1] + self.step / 2, self.step)
        self.sigma = max(sigma_s / self.step, 2.5)  # samples
        self.kernels = gaussian_kernels(self.sigma)
        self.window = len(self.kernels[0])  # the kernel's support, samples
        if len(self.grid) < 2 * self.window:
            raise ValueError("the recording is too short to differentiate its encoder angles")

    def __call__(self, x: np.ndarray, deriv: int = 0) -> np.ndarray:
        xg = x if self.uniform else np.interp(self.grid, self.t, x)
        y = convolve1d(xg, self.kernels[deriv], mode="nearest") / self.step ** deriv
        return y if self.uniform else np.interp(self.t, self.grid, y)

    def edges(self) -> np.ndarray:
        """True where the kernel stays inside the data."""
        margin = self.window // 2 * self.step
        return (self.t >= self.t[0] + margin) & (self.t <= self.t[-1] - margin)


class _Filter:
    """The same filter over each window of a recording on its own: a window
    sampled out of a long recording must not be smoothed across the jump to
    the next one."""

    def __init__(self, t: np.ndarray, sigma_s: float, starts: np.ndarray):
        self.bounds = list(zip(starts, list(starts[1:]) + [len(t)]))
        self.pieces = [_UniformFilter(t[a:b], sigma_s) for a, b in self.bounds]
        self.window = self.pieces[0].window

    def __call__(self, x: np.ndarray, deriv: int = 0) -> np.ndarray:
        if len(self.pieces) == 1:
            return self.pieces[0](x, deriv)
        return np.concatenate([f(x[a:b], deriv) for f, (a, b) in zip(self.pieces, self.bounds)])

    def valid(self) -> np.ndarray:
        return np.concatenate([f.edges() for f in self.pieces])


def kinematics(rec: Recording, sigma_s: float = 0.006, starts: np.ndarray | None = None) -> Kinematics:
    """Speeds and accelerations of motor and link from the encoder angles.

    A 6 ms Gaussian (about 25 Hz bandwidth) turns a 4096-count encoder into a
    usable acceleration at 1 kHz while passing the joint's motion (a few Hz).
    `starts`: first sample of each contiguous window (default: one window)."""
    f = _Filter(rec.time, sigma_s, np.array([0]) if starts is None else np.asarray(starts))
    return Kinematics(f(rec.theta_m, 1), f(rec.theta_m, 2), f(rec.theta_l, 1), f(rec.theta_l, 2), f, f.valid())


REGIME_SIGMA = 0.025  # s: a regime (speed, load, acceleration) holds for tens of milliseconds


def regime_filter(rec: Recording, starts: np.ndarray | None = None, sigma_s: float = REGIME_SIGMA) -> "_Filter":
    """A Gaussian over each window, slow enough that a measured signal through
    it keeps its regime and loses its sample-to-sample noise (narrower where
    a window is too short for it: its kernel must fit twice in each)."""
    starts = np.array([0]) if starts is None else np.asarray(starts)
    shortest = int(np.min(np.diff(np.append(starts, len(rec.time)))))
    fits = (shortest / 2 - 2) / (2 * _TRUNCATE) * float(np.median(np.diff(rec.time)))
    return _Filter(rec.time, min(sigma_s, fits), starts)


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
