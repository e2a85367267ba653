"""structure.order_search reads an order's floor (its off-orders) only where
it can decide something: for a significant order, or when the caller keeps
every order tried (`seen`, for saying why none passed). The orders found are
the same either way; the detection limits, which ask only what passed, are
spared three quarters of the fits."""
import numpy as np

from hdjoint.diagnosis.model import structure
from hdjoint.diagnosis.model.kinematics import folds
from hdjoint.diagnosis.model.structure import candidate_orders, order_search

N, FOLDS = 8000, 40


def _search(residual, theta, seen):
    fold = folds(N, FOLDS)
    test = fold % 2 == 1
    return order_search(theta, residual, fold, ~test, test, candidate_orders("theta_m", float(np.ptp(theta))),
                        name="theta_m", seen=seen)


def test_the_orders_found_do_not_depend_on_keeping_every_order_tried():
    theta = np.linspace(0.0, 40 * 2 * np.pi, N)
    noise = np.random.default_rng(7).standard_normal(N)
    for residual in (noise, noise + 0.3 * np.sin(2.0 * theta + 0.4), noise + 0.2 * np.cos(4.0 * theta)):
        seen = []
        kept = _search(residual, theta, seen)
        spared = _search(residual, theta, None)
        assert [(o.order, o.amplitude, o.gain.gain, o.prominence) for o in kept] == \
            [(o.order, o.amplitude, o.gain.gain, o.prominence) for o in spared]
        assert all(np.isfinite(o.prominence) for o in seen)  # every floor read when every order is kept


def test_an_order_that_cannot_pass_gets_no_floor_unless_every_order_is_kept(monkeypatch):
    theta = np.linspace(0.0, 40 * 2 * np.pi, N)
    residual = np.random.default_rng(7).standard_normal(N) + 0.3 * np.sin(2.0 * theta + 0.4)
    found = []
    _search(residual, theta, found)
    insignificant = [o.order for o in found if not o.gain.significant]
    assert insignificant and any(o.gain.significant for o in found)
    floors = []  # the off-orders whose floor is fitted
    original = structure._floor_coefficients
    monkeypatch.setattr(structure, "_floor_coefficients", lambda *a, **k: floors.append(a[1]) or original(*a, **k))
    _search(residual, theta, None)
    significant = {o.order for o in found if o.gain.significant}
    assert floors and {round(f - min(significant, key=lambda k: abs(k - f)), 6) for f in floors} <= \
        {round(d, 6) for d in np.array(structure.OFF_ORDERS) * structure._off_order_stretch(theta)}


def test_the_anchors_solve_made_once_is_lstsqs_own_even_where_the_columns_are_degenerate():
    """detection_limit._anchor_fit: each size a limit tries fits its planting by
    the same anchor columns, so their least-squares solve is made once; it
    must give what np.linalg.lstsq gave (cut-off included) for any signature."""
    from hdjoint.diagnosis.verdict.detection_limit import _anchor_fit
    rng = np.random.default_rng(3)
    jacobian = rng.standard_normal((2, 500, 4))
    jacobian[..., 3] = jacobian[..., 0] - 2.0 * jacobian[..., 1]  # an anchor the others already span
    rows = np.sort(rng.choice(500, 300, replace=False))
    _, solve = _anchor_fit(jacobian, rows)
    for _ in range(3):
        signature = rng.standard_normal((2, 500))
        wanted = np.linalg.lstsq(jacobian[:, rows, :].reshape(-1, 4), signature[:, rows].ravel(), rcond=None)[0]
        np.testing.assert_allclose(solve @ signature[:, rows].ravel(), wanted, rtol=1e-10, atol=1e-12)
