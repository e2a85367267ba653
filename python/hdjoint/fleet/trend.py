"""Which joints drift: per joint, each tracked quantity's calibrated value
over time, and a trend test on it.

The test is a weighted least-squares slope t-test: value = a + b*days,
weights 1/se^2 from the 95 % intervals when every point has one (else
equal weights), the residual scale estimated from the scatter (so intervals
that are too narrow or too wide by a common factor do not change the
false-alarm rate), two-sided, n-2 degrees of freedom. A joint's drift
p-value is the smallest of its quantities' p-values times their number
(Bonferroni), so a joint without drift is flagged with probability at most
ALPHA whatever the number of quantities. benchmarks/bench_fleet.py measures
the false-alarm rate (docs/results/fleet.md).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime

import numpy as np
from scipy import stats

from hdjoint.diagnosis import EFFECTS, INTERVAL_Z

ALPHA = 0.05
# A drift matters when the fitted change over the observed period reaches the
# parameter's stated tolerance (the diagnosis' `tolerance`), or this share of
# its first value where none is stated: a significant but tiny trend is not
# a joint to service.
RELEVANT_CHANGE = 0.10

# The kinematic error's amplitude (RMS over a revolution of its harmonic
# terms), at the motor angle's orders (wave generator: eq. (7) aw/bw and the
# extra ke_m slots) and at the link angle's (al1/bl1, ke_l slots) apart: the
# link orders move slowly in most recordings and trade off against gravity,
# so their scatter must not drown the motor orders' trend.
KINEMATIC_MOTOR = "kinematic_error_motor_orders"
KINEMATIC_LINK = "kinematic_error_link_orders"
KINEMATIC_TERMS = {KINEMATIC_MOTOR: (("aw1", "bw1", "aw2", "bw2"), "param.ke_m"),
                   KINEMATIC_LINK: (("al1", "bl1"), "param.ke_l")}
# What is followed over time, in the order the report shows it.
TRACKED = ("Fc", KINEMATIC_MOTOR, KINEMATIC_LINK, "Kf", "Kt", "Jm", "Bm", "Cf", "Kw", "Fs", "hys_H", "backlash")
# Parameters that are not an effect's of the library: named for the report.
NAMED = {"Kf": "flexspline stiffness", "Kt": "torque constant", "Jm": "motor inertia",
         KINEMATIC_MOTOR: "kinematic_error", KINEMATIC_LINK: "kinematic_error"}


def effect_of(quantity: str) -> str:
    """The effect ID (or plain name) a tracked quantity belongs to."""
    for effect in EFFECTS.values():
        if quantity in effect.params:
            return effect.id
    return NAMED.get(quantity, quantity)


@dataclass(frozen=True)
class Trend:
    quantity: str
    n: int
    slope_per_day: float
    change: float      # fitted change over the observed span, relative to the first value
    t: float
    p_value: float     # two-sided, of this quantity alone
    relevant: bool     # the change reaches the tolerance (or RELEVANT_CHANGE)
    needed: float = math.nan  # the change that is relevant, relative to the first value (as `change`)


@dataclass(frozen=True)
class JointDrift:
    joint: str
    p_value: float     # Bonferroni over the joint's tested quantities
    drifting: bool
    strongest: Trend | None
    trends: tuple[Trend, ...]

    @property
    def effect(self) -> str:
        return effect_of(self.strongest.quantity) if self.strongest else ""

    @property
    def direction(self) -> str:
        if not self.strongest:
            return ""
        return "growing" if self.strongest.slope_per_day > 0 else "shrinking"


def _days(dates: list[str]) -> np.ndarray:
    """Days since the first date; dates that are not ISO fall back to their rank."""
    try:
        stamps = [datetime.fromisoformat(d) for d in dates]
    except (TypeError, ValueError):
        return np.argsort(np.argsort(dates)).astype(float)
    first = min(stamps)
    return np.array([(s - first).total_seconds() / 86400.0 for s in stamps])


def _get(row: dict, column: str) -> float:
    v = row.get(column)
    try:
        return float(v)
    except (TypeError, ValueError):
        return math.nan


def kinematic_terms(row: dict, quantity: str) -> list[str]:
    eq7, prefix = KINEMATIC_TERMS[quantity]
    extra = [c[len("param."):] for c in row if c.startswith(prefix) and c.endswith(("_a", "_b"))]
    return list(eq7) + extra


def quantity(row: dict, name: str) -> tuple[float, float, float]:
    """(value, lo, hi) of a tracked quantity in a row; a kinematic error
    amplitude's interval comes from its terms' intervals (first order)."""
    if name not in KINEMATIC_TERMS:
        return _get(row, f"param.{name}"), _get(row, f"param.{name}.lo"), _get(row, f"param.{name}.hi")
    coeffs, ses = [], []
    for slot in kinematic_terms(row, name):
        c = _get(row, f"param.{slot}")
        if not math.isfinite(c):
            continue
        coeffs.append(c)
        ses.append((_get(row, f"param.{slot}.hi") - _get(row, f"param.{slot}.lo")) / (2 * INTERVAL_Z))
    if not coeffs:
        return math.nan, math.nan, math.nan
    c, se = np.array(coeffs), np.array(ses)
    amplitude = float(np.sqrt(np.sum(c * c) / 2))
    if amplitude == 0 or not np.all(np.isfinite(se)):
        return amplitude, math.nan, math.nan
    half = INTERVAL_Z * float(np.sqrt(np.sum((c / (2 * amplitude)) ** 2 * se ** 2)))
    return amplitude, amplitude - half, amplitude + half


def slope_test(days, values, lo=None, hi=None) -> tuple[float, float, float] | None:
    """(slope, t, p) of the weighted slope t-test, or None when it cannot be computed."""
    x, y = np.asarray(days, float), np.asarray(values, float)
    if len(y) < 3 or np.ptp(x) == 0:
        return None
    se = None if lo is None else (np.asarray(hi, float) - np.asarray(lo, float)) / (2 * INTERVAL_Z)
    w = 1.0 / se ** 2 if se is not None and np.all(np.isfinite(se)) and np.all(se > 0) else np.ones_like(y)
    xm, ym = np.sum(w * x) / np.sum(w), np.sum(w * y) / np.sum(w)
    sxx = np.sum(w * (x - xm) ** 2)
    slope = np.sum(w * (x - xm) * (y - ym)) / sxx
    resid = y - ym - slope * (x - xm)
    dof = len(y) - 2
    s2 = np.sum(w * resid ** 2) / dof
    if s2 <= 0:
        return None if slope == 0 else (float(slope), math.copysign(math.inf, slope), 0.0)
    t = slope / math.sqrt(s2 / sxx)
    return float(slope), float(t), float(2 * stats.t.sf(abs(t), dof))


def joint_trend(joint: str, joint_rows: list[dict]) -> JointDrift:
    ok = [r for r in joint_rows if r.get("status") == "ok"]
    days = _days([r.get("date") for r in ok]) if ok else np.array([])
    trends = []
    for name in TRACKED:
        v = np.array([quantity(r, name) for r in ok]).reshape(-1, 3)
        keep = np.isfinite(v[:, 0])
        if keep.sum() < 3 or np.ptp(v[keep, 0]) == 0:  # absent, or never calibrated
            continue
        result = slope_test(days[keep], v[keep, 0], v[keep, 1], v[keep, 2])
        if result is None:
            continue
        slope, t, p = result
        first = v[keep, 0][np.argmin(days[keep])]
        # Relative to the first value; to the typical one when the first is 0 (an effect that appears).
        first = first if first else float(np.mean(np.abs(v[keep, 0])))
        moved = abs(slope) * np.ptp(days[keep])
        tolerance = np.nanmedian([_get(r, f"param.{name}.tol") for r in ok]) if any(
            f"param.{name}.tol" in r for r in ok) else math.nan
        threshold = tolerance if math.isfinite(tolerance) and tolerance > 0 else RELEVANT_CHANGE * abs(first)
        trends.append(Trend(name, int(keep.sum()), slope, math.copysign(moved, slope) / abs(first) if first
                            else math.nan, t, p, bool(moved >= threshold),
                            threshold / abs(first) if first else math.nan))
    if not trends:
        return JointDrift(joint, math.nan, False, None, ())
    strongest = min(trends, key=lambda tr: (not tr.relevant, tr.p_value, -abs(tr.t)))
    p = min(1.0, strongest.p_value * len(trends))
    return JointDrift(joint, p, p < ALPHA and strongest.relevant, strongest, tuple(trends))


def rank_joints(all_rows: list[dict]) -> list[JointDrift]:
    """Every joint: the drifting ones first, each group by drift p-value (ties: larger |t| first)."""
    by_joint: dict[str, list[dict]] = {}
    for r in all_rows:
        by_joint.setdefault(str(r.get("joint")), []).append(r)
    drifts = [joint_trend(j, rs) for j, rs in by_joint.items()]
    return sorted(drifts, key=lambda d: (not d.drifting, math.isnan(d.p_value), d.p_value,
                                         -abs(d.strongest.t) if d.strongest else 0.0, d.joint))
