"""When the encoders were read against the time stamps: a logger that stamps
nominal instants but reads its encoders a little late (by tau_k, iid, std r)
leaves an error omega * tau_k in each reading, which the estimator would take
for motion (jsf_r_time). A reading's residual e against its four neighbours
(the cubic through them, at its stamped time: the motion's curvature and jerk
cancel, which at a few hundred hertz would otherwise pass for jitter) has
variance c0 + f r^2 omega^2, c0 being quantisation and interpolation error, f
the stencil's gain on white timing errors; the slope of e^2 on omega^2 gives r.
Stamps of the actual reading times leave no such slope."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdjoint.io.timebase import GAP_FACTOR

# Residuals have their local mean taken off over this many samples: a slow
# vibration biases e alike for neighbours, the timing error's part (a
# difference of white noise) sums to almost nothing over the window.
HIGH_PASS = 9
# The residual's weights on the readings k-2 .. k+2 on a regular time base
# (the cubic through the four neighbours, at the middle), and its gain on white
# timing errors after the high-pass: the sum of the squared combined weights.
STENCIL = np.array([1.0 / 6.0, -2.0 / 3.0, 1.0, -2.0 / 3.0, 1.0 / 6.0])
_HIGH_PASS_KERNEL = np.eye(1, HIGH_PASS, HIGH_PASS // 2).ravel() - 1.0 / HIGH_PASS
TIMING_GAIN = float(np.sum(np.convolve(STENCIL, _HIGH_PASS_KERNEL) ** 2))
# A sample counts when the encoder moved at least this many of its counts per
# sample: slower, the quantisation and the interpolation error are not yet
# white, and c0 would grow with speed (a slope that is not timing).
MOVING_COUNTS = 4.0
# A jitter whose variance at the moving samples' mean omega^2 is below this
# share of c0 (quantisation at least) changes nothing the filter does: none.
MATERIAL = 0.1
# Too few moving samples to tell a slope: no jitter is measured.
MIN_SAMPLES = 400
# A residual this many times its fitted variance is a wild sample, left out.
WILD = 30.0
# The interval comes from a bootstrap over this many contiguous blocks (the
# residuals are correlated over neighbours and c0 drifts with the motion).
BLOCKS = 40
RESAMPLES = 400


@dataclass(frozen=True)
class ReadingJitter:
    std: float     # s, 0 when the data show none
    lo: float      # s, the interval
    hi: float
    reason: str    # how it was decided, for a person

    def describe(self) -> str:
        """'encoder reading-time jitter: 58 us (41-72 us), measured from the recording'."""
        us = 1e6
        interval = f" ({self.lo * us:.3g}-{self.hi * us:.3g} us)" if self.hi > self.lo else ""
        return f"encoder reading-time jitter: {self.std * us:.3g} us{interval}, {self.reason}"


def reading_jitter(time, readings, coverage: float) -> ReadingJitter:
    """The std of when READINGS (encoder angles, each an array beside TIME,
    s) were taken against their stamps, with its COVERAGE interval (a block
    bootstrap of the slope of e^2 on omega^2, the encoders combined by their
    precision). 0 when the interval of the slope (r^2) reaches 0, for the
    encoders combined or for any one of them (a late reading moves all), or when
    the jitter's share of every encoder's residual variance is below
    MATERIAL: the data show none; 0 too, with the reason, when fewer than
    MIN_SAMPLES samples moved (a short or still recording)."""
    t = np.asarray(time, float)
    pieces = [_pieces(t, np.asarray(y, float)) for y in readings]
    pieces = [p for p in pieces if p is not None]
    if not pieces:
        return ReadingJitter(0.0, 0.0, 0.0, f"not measured: fewer than {MIN_SAMPLES} samples moved the encoders")
    sums = np.stack([_block_sums(p, len(t)) for p in pieces])  # encoder, block, statistic
    draws = np.random.default_rng(0).multinomial(BLOCKS, np.full(BLOCKS, 1.0 / BLOCKS), RESAMPLES)
    slopes = _slope(np.einsum("rb,ebs->ers", draws, sums))  # encoder, resample
    weights = 1.0 / np.maximum(np.var(slopes, axis=1), np.finfo(float).tiny)
    combined = weights @ slopes / weights.sum()
    estimate = float(weights @ _slope(sums.sum(axis=1)) / weights.sum())
    lo, hi = np.quantile(combined, [(1 - coverage) / 2, (1 + coverage) / 2])
    own_lo = np.quantile(slopes, (1 - coverage) / 2, axis=1)

    def root(slope):
        return math.sqrt(max(float(slope), 0.0) / TIMING_GAIN)
    if lo <= 0.0 or np.any(own_lo <= 0.0):  # a late reading moves every encoder: one alone shows its own noise
        return ReadingJitter(0.0, 0.0, root(hi), "none shown by the recording (the interval reaches 0)")
    if max(estimate * p.mean_x / p.c0 for p in pieces) < MATERIAL:
        return ReadingJitter(0.0, root(lo), root(hi), f"none that matters (under {MATERIAL:.0%} of the encoders' "
                             "quantisation noise)")
    return ReadingJitter(root(estimate), root(lo), root(hi), "measured from the recording")


@dataclass(frozen=True)
class _Samples:
    """One encoder's moving samples: their rows, omega^2, e^2 and weights, and the fit's c0 and mean omega^2."""
    index: np.ndarray
    x: np.ndarray
    z: np.ndarray
    w: np.ndarray
    c0: float
    mean_x: float


def _pieces(t: np.ndarray, y: np.ndarray) -> _Samples | None:
    """One encoder's moving samples, or None when too few moved."""
    if len(y) < MIN_SAMPLES:
        return None
    before, after = t[1:-1] - t[:-2], t[2:] - t[1:-1]
    e = np.zeros(len(y) - 2)  # the residual of readings 1 .. n-2; the two at the ends stay out (edge below)
    e[1:-1] = y[2:-2] - _cubic_at_middle(t, y)
    omega = (y[2:] - y[:-2]) / (before + after)
    e = e - np.convolve(e, np.ones(HIGH_PASS) / HIGH_PASS, mode="same")
    steps = np.abs(np.diff(y))
    if not np.any(steps > 0):
        return None  # the encoder never moved
    quantum = float(steps[steps > 0].min())
    edge = HIGH_PASS // 2 + 1  # the high-pass must not reach the two readings without a residual
    moving = np.abs(y[2:] - y[:-2]) >= 2 * MOVING_COUNTS * quantum
    moving[:edge] = moving[len(moving) - edge:] = False
    moving &= np.isfinite(e) & np.isfinite(omega)
    dt = np.diff(t)
    wide = dt > GAP_FACTOR * np.median(dt)  # a gap: the stencil must not span one
    near_gap = np.convolve(wide, np.ones(4), mode="full")[2:len(y)] > 0  # steps k-2 .. k+1 of reading k
    moving &= ~near_gap
    index = np.flatnonzero(moving)
    if len(index) < MIN_SAMPLES:
        return None
    x, z = omega[index] ** 2, e[index] ** 2
    keep = np.ones(len(x), bool)
    weight = np.ones(len(x))
    for _ in range(4):  # weighted least squares: e^2's spread grows with its mean; wild samples out
        c0, slope = _fit(x[keep], z[keep], weight[keep])
        # floored: a negative intercept would weigh the slowest samples without bound
        variance = np.maximum(c0 + slope * x, 1e-3 * np.mean(z[keep]))
        keep = z <= WILD * variance
        weight = 1.0 / variance ** 2
    if keep.sum() < MIN_SAMPLES:
        return None
    c0, slope = _fit(x[keep], z[keep], weight[keep])
    white = quantum ** 2 / 8  # c0 is at least the quantisation's, 3/2 q^2/12, however the fit comes out
    return _Samples(index[keep], x[keep], z[keep], weight[keep], max(c0, white), float(x[keep].mean()))


def _cubic_at_middle(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The cubic through readings k-2, k-1, k+1, k+2 at t_k, for k = 2 .. n-3 (Lagrange, on the stamps)."""
    nodes = [t[j:len(t) - 4 + j] for j in (0, 1, 3, 4)]
    values = [y[j:len(y) - 4 + j] for j in (0, 1, 3, 4)]
    at = t[2:-2]
    out = np.zeros(len(at))
    for j, (tj, yj) in enumerate(zip(nodes, values)):
        weight = np.ones(len(at))
        for m, tm in enumerate(nodes):
            if m != j:
                weight *= (at - tm) / (tj - tm)
        out += weight * yj
    return out


def _fit(x, z, w):
    """(intercept, slope) of z on x, weights w."""
    sums = np.array([w.sum(), w @ x, w @ x ** 2, w @ z, w @ (x * z)])
    slope = float(_slope(sums))
    return (sums[3] - slope * sums[1]) / sums[0], slope


def _block_sums(s: _Samples, n: int) -> np.ndarray:
    """The weighted sums of each contiguous block of the recording's N samples."""
    block = np.minimum(s.index * BLOCKS // n, BLOCKS - 1)
    stats = np.column_stack([s.w, s.w * s.x, s.w * s.x ** 2, s.w * s.z, s.w * s.x * s.z])
    out = np.zeros((BLOCKS, 5))
    np.add.at(out, block, stats)
    return out


def _slope(s: np.ndarray) -> np.ndarray:
    """The slope of z on x from the sums S (last axis), vectorised."""
    sw, sx, sxx, sz, sxz = np.moveaxis(s, -1, 0)
    det = sw * sxx - sx * sx
    return np.where(det > 0, (sw * sxz - sx * sz) / np.where(det > 0, det, 1.0), 0.0)
