"""What a recording must show for an effect to be testable at all: named
checks that an effect lists in its `needs`. A check is a function of the
recording's view (its kinematics and the reference torque) that returns why
the recording fails it, or None. A new check is registered with `need`."""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from typing import Callable

import numpy as np

# Each side of zero load must hold this share of the samples, beyond a band
# of 5 % of the torque span, for a dead zone around zero load to be visited.
THROUGH_ZERO_SHARE = 0.01
# Windows over which the motion's frequency is read, and the rank correlation
# with time above which it rises (or falls) with time: a chirp's frequency
# follows time closely, the other excitations' (paper, multisine, sweep,
# constant speeds) does not.
FREQUENCY_WINDOW_S = 2.0
FREQUENCY_FOLLOWS_TIME = 0.9


@dataclass
class RecordingView:
    """What the checks read: the recording, its kinematics and the reference torque."""
    rec: object
    kin: object
    reference_torque: np.ndarray

    @cached_property
    def speed(self) -> np.ndarray:
        return np.abs(self.kin.omega_m)

    @cached_property
    def torque_span(self) -> float:
        t = self.reference_torque
        return float(np.nanpercentile(t, 95) - np.nanpercentile(t, 5))


NEEDS: dict[str, Callable[[RecordingView], str | None]] = {}


def need(name: str):
    """Register a check under `name` (the decorated function returns why the recording fails it, or None)."""
    def register(check):
        NEEDS[name] = check
        return check
    return register


def reversals(x: np.ndarray, threshold: float) -> int:
    s = np.sign(x[np.abs(x) > threshold])
    return int(np.count_nonzero(np.diff(s)))


def share_beyond_zero(reference_torque: np.ndarray, band: float) -> float:
    """The smaller share of samples beyond +band and below -band."""
    t = reference_torque[np.isfinite(reference_torque)]
    return min(float(np.mean(t > band)), float(np.mean(t < -band))) if len(t) else 0.0


def frequency_time_correlation(kin, time: np.ndarray) -> float:
    """Spearman's correlation between time and the motion's frequency
    (rms motor acceleration over rms motor speed, rad/s) in windows of
    FREQUENCY_WINDOW_S; 0 when the run has fewer than five windows."""
    n = int(round(FREQUENCY_WINDOW_S / max(float(np.median(np.diff(time))), 1e-12)))
    count = len(time) // max(n, 1)
    if count < 5:
        return 0.0
    w = np.nan_to_num(kin.omega_m[:count * n]).reshape(count, n)
    a = np.nan_to_num(kin.alpha_m[:count * n]).reshape(count, n)
    frequency = np.sqrt(np.mean(a * a, axis=1)) / np.maximum(np.sqrt(np.mean(w * w, axis=1)), 1e-12)
    rho = spearman(np.arange(count), frequency)
    return float(rho) if np.isfinite(rho) else 0.0


def _average_ranks(x: np.ndarray) -> np.ndarray:
    """Ranks 1..n of `x`, tied values sharing their mean rank (whole or half numbers: exact)."""
    order = np.argsort(x, kind="stable")
    ordered = x[order]
    starts = np.flatnonzero(np.concatenate(([True], ordered[1:] != ordered[:-1])))
    counts = np.diff(np.append(starts, len(x)))
    ranks = np.empty(len(x))
    ranks[order] = np.repeat(starts + 1 + (counts - 1) / 2, counts)
    return ranks


def spearman(x, y) -> float:
    """Spearman's rank correlation of two samples, NaN where either is
    constant or has a NaN: scipy.stats.spearmanr's number, computed as it
    does (Pearson's on average ranks, laid out alike), without importing
    scipy.stats (a third of a second)."""
    x, y = np.asarray(x, float), np.asarray(y, float)
    if len(x) < 2 or np.all(x == x[0]) or np.all(y == y[0]) or np.isnan(x).any() or np.isnan(y).any():
        return float("nan")
    ranks = np.stack([_average_ranks(x), _average_ranks(y)])
    return float(np.corrcoef(ranks.T, rowvar=False)[1, 0])


@need("angle")
def _angle(v: RecordingView):
    if not (np.ptp(v.rec.theta_m) > 2 * np.pi or np.ptp(v.rec.theta_l) > 0.5):
        return "the motor turns less than one revolution"


@need("torque")
def _torque(v: RecordingView):
    if not v.torque_span > 0.5:
        return f"the torque varies by only {v.torque_span:.2f} N.m"


@need("torque_reversals")
def _torque_reversals(v: RecordingView):
    t = v.reference_torque
    if not reversals(t - np.nanmedian(t), 0.05 * max(v.torque_span, 1e-9)) >= 2:
        return "the load reverses fewer than twice"


@need("load_through_zero")
def _load_through_zero(v: RecordingView):
    # A dead zone around zero load is seen only where the load passes through
    # zero; held on one side, it is an offset of the torsion (a0 takes it).
    if not share_beyond_zero(v.reference_torque, 0.05 * v.torque_span) >= THROUGH_ZERO_SHARE:
        return "the load stays on one side of zero (a dead zone around zero load is not visited)"


@need("speed_reversals")
def _speed_reversals(v: RecordingView):
    if not reversals(v.kin.omega_m, 0.5) >= 2:
        return "the motor reverses fewer than twice"


@need("low_speed")
def _low_speed(v: RecordingView):
    if not (np.mean((v.speed > 0.2) & (v.speed < 20.0)) > 0.02 and reversals(v.kin.omega_m, 0.5) >= 2):
        return "the motor passes slowly through zero speed fewer than twice"


@need("speed")
def _speed(v: RecordingView):
    if not np.percentile(v.speed, 95) > 10.0:
        return "the motor never runs faster than 10 rad/s"


@need("current_dynamics")
def _current_dynamics(v: RecordingView):
    if not (np.std(np.diff(v.rec.i_m)) > 0 and np.ptp(v.kin.alpha_m) > 50.0):
        return "the current and acceleration hardly change"


@need("duration")
def _duration(v: RecordingView):
    if not v.rec.duration >= 10.0:
        return f"the recording lasts {v.rec.duration:.1f} s (< 10 s)"


@need("spectrum_steady_in_time")
def _spectrum_steady_in_time(v: RecordingView):
    # On a chirp time is frequency: a drift over the run cannot be told from a
    # mismatch that grows with frequency (a dynamic friction law's mismatch
    # against a static one can pass for thermal_drift).
    if not abs(frequency_time_correlation(v.kin, v.rec.time)) < FREQUENCY_FOLLOWS_TIME:
        return ("the motion's frequency rises or falls steadily over the run (a chirp): "
                "a drift cannot be told from a mismatch that grows with frequency")


@need("link_travel")
def _link_travel(v: RecordingView):
    if not np.ptp(v.rec.theta_l) > 0.05:
        return "the link moves less than 0.05 rad"


@need("link_reversals")
def _link_reversals(v: RecordingView):
    if not reversals(v.kin.omega_l, 0.005) >= 2:
        return "the link reverses fewer than twice"


def testable(effect, prep, reference_torque: np.ndarray) -> str | None:
    """None when the recording excites the effect; otherwise why it cannot be
    tested (the first of its `needs` the recording fails). Each check is
    evaluated only for an effect that needs it."""
    view = RecordingView(prep.rec, prep.kin, reference_torque)
    return next((why for name in effect.needs if (why := NEEDS[name](view)) is not None), None)
