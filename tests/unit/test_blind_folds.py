"""Held-out folds where a channel compares nothing (the motor at rest: its
residual is 0 before and after every hypothesis) say nothing about a
hypothesis. Counted as folds of zero gain they capped a motor effect's z on
a sweep with dwells, and kept the share of improved folds below the 70 %
the acceptance asks for; in the order search a fold of rest made the z of
every ripple 0, and cogging on that sweep was never tested."""
import numpy as np
import pytest

from hdjoint.diagnosis.search.significance import null_z
from hdjoint.diagnosis.model.kinematics import folds
from hdjoint.diagnosis.model.structure import fold_z, held_out_gain_sq, order_search

N, FOLDS = 8000, 40
SMOOTHING = 8.0  # samples


def _layout():
    fold = folds(N, FOLDS)
    test = fold % 2 == 1
    blind = np.isin(fold, np.arange(3, FOLDS, 4))  # every other held-out fold rests: half of them blind
    return fold, test, blind


def test_blind_folds_are_left_out_of_the_fold_z():
    rng = np.random.default_rng(1)
    fold, test, blind = _layout()
    before = rng.chisquare(1, N)
    after = before * (0.8 + 0.02 * rng.standard_normal(N))  # a steady 20 % gain where the channel looks
    seen = held_out_gain_sq(before, after, fold, test)
    before[blind], after[blind] = 0.0, 0.0
    masked = held_out_gain_sq(before, after, fold, test)
    assert masked.folds_compared == seen.folds_compared // 2
    assert masked.folds_improved == masked.folds_compared  # not 50 % of all folds: the acceptance's 70 % holds
    # Over the folds that look, the same evidence as a recording of that length alone (no flood of zeros).
    looking = np.isfinite(masked.fold_gains)
    assert masked.z == pytest.approx(np.mean(seen.fold_gains[looking]) / (
        np.std(seen.fold_gains[looking], ddof=1) / np.sqrt(looking.sum())), rel=1e-9)


def test_order_search_finds_a_ripple_beside_rests():
    """A ripple of the motor angle in a residual that is NaN over whole folds (where the motor rests)."""
    rng = np.random.default_rng(2)
    fold, test, blind = _layout()
    theta = np.linspace(0.0, 60 * 2 * np.pi, N)
    residual = 0.3 * np.cos(4.0 * theta + 0.4) + rng.standard_normal(N)
    residual[blind] = np.nan
    found = order_search(theta, residual, fold, ~test, test, [k / 2 for k in range(1, 13)])
    assert found and found[0].order == 4.0
    assert found[0].gain.z > 3.0 and found[0].gain.folds_compared == 10


def test_null_z_leaves_out_the_same_folds():
    """The simulated null's statistic is the observed one's: on a replicate,
    null_z equals held_out_gain_sq's z of the same linear fit on the samples
    the channel looks at (the blind ones deleted)."""
    rng = np.random.default_rng(3)
    fold, test, blind = _layout()
    train = ~test
    x = np.linspace(0.0, 20.0, N)
    jac = np.stack([np.sin(x), np.cos(3 * x)], axis=1)[None, :, :]  # (channel, sample, parameter)
    jac[:, blind, :] = 0.0
    noise = rng.standard_normal((5, 1, N))
    noise[:, :, blind] = 0.0
    z = null_z(noise, jac, np.flatnonzero(train), fold, test)
    for replicate in range(len(noise)):
        e = noise[replicate, 0]
        delta = np.linalg.lstsq(jac[0][train], e[train], rcond=None)[0]
        look = ~blind
        direct = held_out_gain_sq(e[look] ** 2, (e - jac[0] @ delta)[look] ** 2, fold[look], test[look])
        assert np.isfinite(z[replicate])
        assert z[replicate] == pytest.approx(direct.z, rel=1e-6)


def _sweep_angle(n):
    """A motor angle that goes back and forth over uneven ranges (point-to-point
    moves with reversals, as the benchmark's sweep), about 26 revolutions end to end."""
    targets = 2 * np.pi * 100 * np.array([0.0, 0.7, -0.4, 0.9, -0.8, 0.3, -0.6, 0.8, 0.0, -0.5, 0.6, 0.0]) / 6.6
    x = np.linspace(0.0, len(targets) - 1, n, endpoint=False)
    k, s = x.astype(int), x % 1.0
    return targets[k] + (targets[k + 1] - targets[k]) * s ** 3 * (10 - 15 * s + 6 * s * s)


def test_a_strong_ripple_stands_out_of_its_own_leakage():
    """Cogging on the sweep: the order's fit leaks into its off-orders as the
    sweep visits angles unevenly; the floor is read off what the order leaves."""
    from scipy.ndimage import gaussian_filter1d
    rng = np.random.default_rng(4)
    fold, test, _ = _layout()
    theta = _sweep_angle(N)
    smoothed = lambda x: gaussian_filter1d(x, SMOOTHING)  # noqa: E731 (the motor channel's filter)
    residual = smoothed(0.15 * np.cos(6.0 * theta + 1.0)) + 0.005 * rng.standard_normal(N)
    found = order_search(theta, residual, fold, ~test, test, [k / 2 for k in range(1, 25)], through=smoothed)
    assert found and found[0].order == 6.0 and found[0].prominence > 3.0


def test_no_fold_compared_is_no_evidence():
    assert fold_z(np.array([np.nan, np.nan, np.nan])) == 0.0


def test_a_ripple_that_explains_most_of_the_residual_counts_over_a_broadband_floor():
    """Cogging seen through a lag beside the lag's own broadband residual: the
    off-orders carry power (prominence under 3), but the order alone explains
    most of the held-out residual. A weaker order over the same floor does not count."""
    rng = np.random.default_rng(7)
    fold, test, _ = _layout()
    theta = _sweep_angle(N)
    # Structure spread over the angle's spectrum beside order 8 (where its off-orders lie), at no order of the grid.
    spread = np.concatenate([rng.uniform(7.6, 7.85, 60), rng.uniform(8.15, 8.4, 60)])
    broadband = sum(np.cos(k * theta + rng.uniform(0, 2 * np.pi)) for k in spread)
    broadband *= 0.1 / np.std(broadband)
    orders = [k / 2 for k in range(1, 25)]
    strong = order_search(theta, 0.1 * np.cos(8.0 * theta) + broadband, fold, ~test, test, orders, seen=(seen := []))
    at8 = next(o for o in seen if o.order == 8.0)
    assert at8.prominence <= 3.0 and at8.gain.gain > 0.3  # the broadband floor hides it from the prominence ...
    assert [o.order for o in strong][:1] == [8.0]           # ... not from its share of the residual
    weak = order_search(theta, 0.02 * np.cos(8.0 * theta) + broadband, fold, ~test, test, orders, seen=(seen := []))
    at8 = next(o for o in seen if o.order == 8.0)
    assert at8.gain.gain < 0.3 and 8.0 not in [o.order for o in weak if o.prominence <= 3.0]
