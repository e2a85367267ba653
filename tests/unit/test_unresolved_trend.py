"""structure.unresolved_trend: over a short travel a low order's ripple, one
the order search cannot resolve, leaks into the lowest orders it can. Fitted
beside a cubic trend along the angle, no resolved order takes it up, and a
resolved ripple is still found beside it."""
import numpy as np

from hdjoint.diagnosis.model.kinematics import folds
from hdjoint.diagnosis.model.structure import (candidate_orders, lowest_unresolved_order, order_search, unresolved_order,
    unresolved_trend)

N, FOLDS, TRAVEL = 8000, 40, 2.4  # rad of link travel: the independent truth's paper run


def _sweep():
    """Three passes over TRAVEL, out and back and out, with noise of unit size."""
    phase = np.linspace(0.0, 3.0, N)
    theta = 0.3 + TRAVEL * np.abs(((phase + 1.0) % 2.0) - 1.0)
    return theta, np.random.default_rng(4).standard_normal(N)


def _search(theta, residual, trend):
    fold = folds(N, FOLDS)
    test = fold % 2 == 1
    return order_search(theta, residual, fold, ~test, test, candidate_orders("theta_l", TRAVEL), name="theta_l",
                        trend=trend)


def test_a_low_order_ripple_alone_is_no_resolved_order():
    theta, noise = _sweep()
    residual = 1.5 * np.cos(2.0 * theta + 0.3) + noise  # order 2: 0.76 of a period over the travel
    assert min(candidate_orders("theta_l", TRAVEL)) == 4.0
    assert _search(theta, residual, unresolved_trend(theta, "theta_l")) == []


def test_a_resolved_ripple_beside_an_unresolved_one_is_found_with_the_trend_and_missed_without():
    """Left in, the unresolved ripple is locally an offset that swamps the
    resolved order's held-out gain fold by fold (z 1.5 without the trend)."""
    theta, noise = _sweep()
    residual = 1.5 * np.cos(2.0 * theta + 0.3) + 0.4 * np.sin(12.0 * theta) + noise
    assert 12.0 not in [o.order for o in _search(theta, residual, None)]
    found = _search(theta, residual, unresolved_trend(theta, "theta_l"))
    assert [o.order for o in found][:1] == [12.0]
    assert all(o.order == 12.0 or o.gain.gain < found[0].gain.gain / 3 for o in found)


def test_no_trend_where_the_travel_resolves_every_order_of_the_grid():
    theta = np.linspace(0.0, 60 * 2 * np.pi, N)
    assert unresolved_trend(theta, "theta_m") is None
    assert unresolved_trend(theta, "theta_l") is None
    assert unresolved_trend(np.linspace(0.0, 2.0, N), "theta_m").shape == (3, N)


def test_the_lowest_unresolved_link_order_the_model_lacks():
    theta, _ = _sweep()
    assert lowest_unresolved_order(theta, "theta_l") == 1.0
    assert lowest_unresolved_order(theta, "theta_l", exclude=(1.0,)) == 2.0  # eq. (7) has omega_l = 1
    assert lowest_unresolved_order(np.linspace(0.0, 20.0, N), "theta_l", exclude=(1.0,)) is None


def test_an_unresolved_order_takes_up_slow_structure_along_the_angle_and_not_noise():
    """The order the search cannot resolve (nothing found above) is still
    slow structure along the angle: fitted as the lowest unresolved order
    it predicts the held-out folds of a ripple at another low order, and
    nothing of pure noise."""
    theta, noise = _sweep()
    fold = folds(N, FOLDS)
    test = fold % 2 == 1
    ripple = unresolved_order(theta, 1.5 * np.cos(3.0 * theta + 0.3) + noise, fold, ~test, test, 2.0, "theta_l")
    assert not ripple.resolved and ripple.order == 2.0 and ripple.angle == "theta_l"
    assert ripple.gain.gain > 0.25  # of at most 0.53 (the ripple's share of the variance)
    alone = unresolved_order(theta, noise, fold, ~test, test, 2.0, "theta_l")
    assert alone.gain.gain < 0.005
