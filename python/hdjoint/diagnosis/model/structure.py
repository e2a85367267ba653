"""Where a residual carries structure, and whether it is real.

Every test here fits on the even folds and is judged on the odd (held-out)
folds, fold by fold, so structure means "predicts residual it did not see",
not "looks like a pattern": white noise and encoder quantisation average out
of bin means and leave no held-out gain.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from hdjoint.diagnosis.rules import DOMINANT_GAIN, EVIDENCE_Z, ORDER_PROMINENCE, STRUCTURE_GAIN


@dataclass
class HeldOutGain:
    """How much of the held-out residual variance a description explains."""
    gain: float      # 1 - MSE_after/MSE_before on held-out data
    z: float         # mean fold improvement / its standard error
    fold_gains: np.ndarray  # relative gain per held-out fold; NaN where the fold compares nothing

    @property
    def significant(self) -> bool:
        return self.gain > STRUCTURE_GAIN and self.z > EVIDENCE_Z

    @property
    def folds_compared(self) -> int:
        return int(np.count_nonzero(np.isfinite(self.fold_gains)))

    @property
    def folds_improved(self) -> int:
        return int(np.count_nonzero(self.fold_gains > 0))


def fold_z(relative: np.ndarray) -> float:
    """Mean over the folds that compare something (finite) / its standard error."""
    r = relative[np.isfinite(relative)]
    if not len(r):
        return 0.0  # no fold compares anything: no evidence
    spread = np.std(r, ddof=1) / np.sqrt(len(r)) if len(r) > 1 else np.inf
    return float(np.mean(r) / spread) if spread > 0 else (np.inf if len(r) and np.mean(r) > 0 else 0.0)


def relative_fold_gains(before: np.ndarray, after: np.ndarray) -> np.ndarray:
    """(before - after) / before per fold; NaN for a fold that compares
    nothing (before = 0: a channel blind there, as the motor's at rest), which
    says nothing either way. Counted as gains of 0, such folds would cap the
    z of a motor effect and its share of improved folds on a recording whose
    motor rests in many folds."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(before > 0, (before - after) / np.where(before > 0, before, 1.0), np.nan)


def held_out_gain(residual, prediction, fold, test) -> HeldOutGain:
    """Gain of subtracting `prediction` from `residual`, on the test folds."""
    return held_out_gain_sq(residual ** 2, (residual - prediction) ** 2, fold, test)


def held_out_gain_sq(before, after, fold, test) -> HeldOutGain:
    """Gain from per-sample squared errors before and after, on the test folds.

    z is taken over the folds' *relative* gains: an effect that grows with
    the motion (most do) improves loud folds more than quiet ones in
    absolute terms, but by a similar fraction."""
    labels, which = np.unique(fold[test], return_inverse=True)
    b = _fold_means(before[test], which, len(labels))
    a = _fold_means(after[test], which, len(labels))
    relative = relative_fold_gains(b, a)
    gain = 1.0 - np.nanmean(after[test]) / np.nanmean(before[test])
    return HeldOutGain(float(gain), fold_z(relative), relative)


def _fold_means(x, which, count):
    """The mean of the finite values of `x` in each fold (`which`: each value's fold index)."""
    ok = np.isfinite(x)
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.bincount(which[ok], x[ok], count) / np.bincount(which[ok], minlength=count)


def bins_of(feature, residual, bins: int = 20, circular_period: float | None = None):
    """Each sample's bin of `feature` (quantile bins, or equal ones over a
    period), the bin edges, and where both are finite; None when too few bins."""
    x = np.mod(feature, circular_period) if circular_period else feature
    ok = np.isfinite(x) & np.isfinite(residual)
    if circular_period:
        edges = np.linspace(0.0, circular_period, bins + 1)
    else:
        edges = np.unique(np.nanpercentile(x[ok], np.linspace(0, 100, bins + 1)))
    if len(edges) < 3:
        return None, edges, ok
    return np.clip(np.searchsorted(edges, x, side="right") - 1, 0, len(edges) - 2), edges, ok


def binned_prediction(feature, residual, train, bins: int = 20, circular_period: float | None = None,
                      modulator=None):
    """Per-bin mean of the training residual, applied everywhere (NaN-free);
    with a `modulator` m, per-bin least-squares coefficients of the residual
    on m, applied as coefficient times m (structure that scales with m)."""
    index, edges, ok = bins_of(feature, residual, bins, circular_period)
    if index is None:
        return np.zeros_like(residual), edges, np.zeros(1)
    m = np.ones_like(residual) if modulator is None else modulator
    use = ok & train
    sums = np.bincount(index[use], weights=residual[use] * m[use], minlength=len(edges) - 1)
    weights = np.bincount(index[use], weights=m[use] * m[use], minlength=len(edges) - 1)
    counts = np.bincount(index[use], minlength=len(edges) - 1)
    means = np.where((counts > 20) & (weights > 0), sums / np.where(weights > 0, weights, 1.0), 0.0)
    return means[index] * m, edges, means


@dataclass
class Structure:
    feature: str
    gain: HeldOutGain
    peak_at: str      # where along the feature the residual is largest
    edges: np.ndarray
    means: np.ndarray
    bin_index: np.ndarray | None = None  # each sample's bin (the regressors of the binned prediction)
    modulator: np.ndarray | None = None  # what each bin's coefficient multiplies (None: 1)


def scan(residual, features: dict, fold, train, test, through=None) -> list[Structure]:
    """Binned-mean scans over named features; returns them sorted by held-out gain.
    `features` maps name -> (values, circular period or None, unit), or with
    a fourth item that words a bin (lo, hi) for a feature whose values are
    coded (None: the plain words), and a fifth, a modulator the bins' values
    multiply (binned_prediction).
    `through`: the filter the residual was seen through, which each prediction
    passes too (a ripple in the motor angle at speed reaches a smoothed channel
    attenuated: predicted at full size, it makes fast folds worse)."""
    found = []
    centred = residual - np.nanmean(residual[train])
    for name, (values, period, unit, *more) in features.items():
        words, modulator = (more + [None, None])[:2]
        pred, edges, means = binned_prediction(values, centred, train, circular_period=period, modulator=modulator)
        if through is not None:
            pred = through(pred)
        gain = held_out_gain(centred, pred, fold, test)
        k = int(np.argmax(np.abs(means))) if len(means) else 0
        bin_text = words or (lambda lo, hi: f"{lo:.3g} to {hi:.3g} {unit}")
        where = bin_text(edges[k], edges[k + 1]) if len(edges) > k + 1 else ""
        found.append(Structure(name, gain, where, edges, means, bins_of(values, centred, circular_period=period)[0],
                               modulator))
    return sorted(found, key=lambda s: -s.gain.gain)


@dataclass
class Order:
    angle: str       # "theta_m" or "theta_l"
    order: float     # cycles per revolution
    amplitude: float  # of the residual component, residual units
    gain: HeldOutGain
    prominence: float  # power at this order over the median power at off-orders
    channel: str = ""  # the residual it was found in, when several were searched
    # False for an order the travel does not resolve (unresolved_order): it stands
    # for whatever low order of the angle the travel cannot tell from it.
    resolved: bool = True


# Periods of a ripple a recording's travel must cover for the ripple to be
# told from a drift, an offset or anything else that changes along the travel.
RESOLVING_PERIODS = 1.5


def resolving_travel(order: float) -> float:
    """The travel (rad of an angle) that resolves a ripple of `order` cycles per revolution."""
    return 2 * np.pi * RESOLVING_PERIODS / order


def resolves(order: float, travel: float) -> bool:
    """Whether `travel` (rad of an angle) resolves a ripple of `order` cycles per revolution."""
    return travel >= resolving_travel(order)


def _order_grid(angle: str) -> list[float]:
    return [k / 2 for k in range(1, 25)] if angle == "theta_m" else [float(k) for k in range(1, 41)]


def candidate_orders(angle: str, travel: float) -> list[float]:
    """The order grid searched on `angle` ("theta_m": half orders up to 12,
    "theta_l": whole orders up to 40), keeping the orders the recording's
    travel (rad) resolves."""
    return [k for k in _order_grid(angle) if resolves(k, travel)]


# A harmonic the travel does not resolve spans fewer than 3 half-periods of
# it: a polynomial of this degree in the angle takes it up.
TREND_DEGREE = 3


def unresolved_trend(values: np.ndarray, angle: str, through=None) -> np.ndarray | None:
    """(column, sample): Legendre polynomials of degree 1..TREND_DEGREE in
    `angle` over its travel, when the travel leaves some of the grid's orders
    unresolved (None otherwise). An order is fitted beside them: over a short
    travel a low order's ripple, one the search cannot resolve, leaks into the
    lowest orders it can, where it would be found as an order the joint lacks
    (benchmarks/order_gate_scan.py measures the order search's gates)."""
    lo, hi = float(np.min(values)), float(np.max(values))
    if all(resolves(k, hi - lo) for k in _order_grid(angle)) or hi <= lo:
        return None
    x = 2.0 * (values - lo) / (hi - lo) - 1.0
    columns = np.polynomial.legendre.legvander(x, TREND_DEGREE)[:, 1:].T
    return np.stack([through(c) for c in columns]) if through is not None else columns


def unresolved_orders(angle: str, travel: float) -> list[float]:
    """The orders of `angle`'s grid that `travel` (rad) does not resolve."""
    return [k for k in _order_grid(angle) if not resolves(k, travel)]


def lowest_unresolved_order(values: np.ndarray, angle: str, exclude=()) -> float | None:
    """The lowest order of `angle`'s grid that the travel does not resolve
    and the model does not have (`exclude`), or None."""
    return next((k for k in unresolved_orders(angle, float(np.ptp(values)))
                 if all(abs(k - e) > 1e-9 for e in exclude)), None)


def unresolved_order(values, residual, fold, train, test, order: float, name: str) -> Order:
    """An order the travel does not resolve, fitted alone with a constant:
    over a fraction of its period its cosine and sine are two smooth curves
    of the angle, so its gain is that of slow structure along the angle,
    whatever its true low order. Fold by fold such structure is as uneven as
    the angle's visits to each place: it is judged pooled against the
    simulated null (HypothesisSearch.try_effect), never by its folds or its spectrum."""
    ok = np.isfinite(residual)
    res = np.where(ok, residual, 0.0)
    basis = _basis(values, order, None)
    coef = _harmonic_coefficients(basis, res, train & ok)
    pred = coef[:2] @ basis[:2]
    return Order(name, float(order), float(np.hypot(coef[0], coef[1])),
                 held_out_gain(res, np.where(ok, pred, 0.0), fold, test & ok), float("nan"), resolved=False)


def _basis(angle, order, through, trend=None):
    """cos, sin of `order` x `angle` (through the channel's filter, if it has
    one: a ripple the channel sees smoothed fades with speed), a constant,
    and the angle's unresolved trend, if any."""
    c, s = np.cos(order * angle), np.sin(order * angle)
    if through is not None:
        c, s = through(c), through(s)
    columns = np.stack([c, s, np.ones_like(angle)])
    return columns if trend is None else np.concatenate([columns, trend])


def _harmonic_coefficients(basis, residual, rows):
    fit = basis[:, rows]
    return np.linalg.solve(fit @ fit.T, fit @ residual[rows])


def harmonic_amplitude(angle, values, order: float) -> np.ndarray:
    """The amplitude of `order` x `angle` in `values` (a sample, or columns of
    them), fitted by least squares with a constant."""
    coef = _harmonic_coefficients(_basis(angle, order, None), values, slice(None))
    return np.hypot(coef[0], coef[1])


def _floor_coefficients(angle, order, through, residual, rows, trend=None):
    """_harmonic_coefficients at an off-order, on `rows`: without a filter the
    basis is needed there only (the same numbers, a fraction of the cost)."""
    if through is not None:
        return _harmonic_coefficients(_basis(angle, order, through, trend), residual, rows)
    return _harmonic_coefficients(_basis(angle[rows], order, None, None if trend is None else trend[:, rows]),
                                  residual[rows], slice(None))



# Off-orders giving an order's floor: a quarter order beside it, where the
# recording turns the angle often enough to resolve a quarter order.
OFF_ORDERS = (-0.27, 0.23, 0.31)


def _off_order_stretch(angle) -> float:
    """How far the off-orders must move out so each lies beyond the order's own
    main lobe (1.1 / revolutions): a least-squares fit at k + d of a ripple at k
    over R revolutions picks up sinc(d R) of it. Over a few revolutions the
    quarter-order off-orders sit inside the lobe: a pure ripple would show a
    prominence near 1 and read as broadband."""
    revolutions = max(float(np.ptp(angle)) / (2 * np.pi), 1e-9)
    return max(1.0, 1.1 / (min(abs(d) for d in OFF_ORDERS) * revolutions))


def order_search(angle, residual, fold, train, test, orders, exclude=(), name="theta_m",
                 max_orders: int = 2, through=None, seen: list | None = None, trend=None) -> list[Order]:
    """Angle-synchronous analysis: least-squares power of the residual at each
    candidate order of `angle`; an order counts when its held-out gain is
    significant and it stands out of the spectrum (off-orders, at +1/4,
    give the floor that broadband structure and noise produce), or alone
    explains more than DOMINANT_GAIN of the held-out residual. `through`:
    the smoothing filter the residual channel sees the world through;
    `seen`: a list that receives every order evaluated, significant or not;
    `trend`: columns fitted beside each order (unresolved_trend). Without
    `seen`, an order that is not significant has no use for its floor, and
    its off-orders (three quarters of the cost) are not fitted."""
    ok = np.isfinite(residual)
    res = np.where(ok, residual, 0.0)
    train, test = train & ok, test & ok
    if trend is not None:
        # Judged on what the trend leaves: the unresolved ripple, locally an
        # offset, would otherwise swamp an order's held-out gain fold by fold.
        smooth = np.concatenate([np.ones((1, len(res))), trend])
        res = np.where(ok, res - _harmonic_coefficients(smooth, res, train) @ smooth, 0.0)
    # The floor needs no held-out prediction: every 4th training sample will do.
    floor_rows = np.flatnonzero(train)[::4]
    offsets = np.array(OFF_ORDERS) * _off_order_stretch(angle)
    found = []
    for k in orders:
        if any(abs(k - e) < 1e-9 for e in exclude):
            continue
        basis = _basis(angle, k, through, trend)
        coef = _harmonic_coefficients(basis, res, train)
        pred, amp = coef[:2] @ basis[:2], float(np.hypot(coef[0], coef[1]))
        # The floor is read off what the order leaves: a strong ripple's own
        # leakage into its off-orders (a sweep visits its angles unevenly) is
        # not broadband structure. Left in, it would hold even a strong ripple
        # under ORDER_PROMINENCE.
        gain = held_out_gain(res, pred, fold, test)
        if seen is None and not gain.significant:
            found.append(Order(name, float(k), amp, gain, float("nan")))
            continue
        rest = np.where(ok, res - pred, 0.0)
        floor = np.median([np.hypot(*_floor_coefficients(angle, k + d, through, rest, floor_rows, trend)[:2])
                           for d in offsets])
        found.append(Order(name, float(k), amp, gain, amp / max(floor, 1e-300)))
    if seen is not None:
        seen.extend(found)
    good = [o for o in found if o.gain.significant and (o.prominence > ORDER_PROMINENCE or o.gain.gain > DOMINANT_GAIN)]
    return sorted(good, key=lambda o: -o.gain.gain)[:max_orders]
