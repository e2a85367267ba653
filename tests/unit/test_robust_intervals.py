"""The calibration's robust (sandwich) posterior: equal to the Laplace one
on white residuals, and honest where the residuals are correlated in blocks
(what model-form error and coloured noise leave), where Laplace is too narrow."""
import numpy as np

from hdjoint.diagnosis.fit.priors import posterior_std, robust_std

Z95 = 1.959964


def _fit(y, x, blocks, prior_std=None):
    """Least squares of y = a + b*x (+ a weak prior on both), returning b, its Laplace and robust std."""
    design = np.stack([np.ones_like(x), x], axis=1)
    sigma = np.std(y - design @ np.linalg.lstsq(design, y, rcond=None)[0])
    rows = [design / sigma]
    targets = [y / sigma]
    if prior_std is not None:  # priors at 0, as extra rows like the diagnosis's
        rows.append(np.eye(2) / prior_std)
        targets.append(np.zeros(2))
    jac, target = np.vstack(rows), np.concatenate(targets)
    beta = np.linalg.lstsq(jac, target, rcond=None)[0]
    residual = jac @ beta - target
    scale = np.ones(2)
    return beta[1], posterior_std(jac, scale)[1], robust_std(jac, residual, blocks, scale)[1]


def _coverage(noise, repeats=300, prior_std=None):
    rng = np.random.default_rng(7)
    n, width = 2000, 40
    x = np.sin(np.linspace(0.0, 30.0, n)) + 0.3 * rng.standard_normal(n)
    blocks = np.arange(n) // width
    hits = {"laplace": 0, "robust": 0}
    for _ in range(repeats):
        y = 1.0 + 2.0 * x + noise(rng, n, blocks)
        b, laplace, robust = _fit(y, x, blocks, prior_std)
        hits["laplace"] += abs(b - 2.0) <= Z95 * laplace
        hits["robust"] += abs(b - 2.0) <= Z95 * robust
    return {k: v / repeats for k, v in hits.items()}


def test_robust_matches_laplace_on_white_residuals():
    cover = _coverage(lambda rng, n, blocks: 0.5 * rng.standard_normal(n))
    assert 0.91 <= cover["laplace"] <= 0.99
    assert 0.90 <= cover["robust"] <= 0.99


def test_robust_covers_where_laplace_does_not_when_residuals_come_in_blocks():
    # Each block of 40 samples shares a slowly varying error proportional to x:
    # a model-form error that changes along the recording.
    def blocky(rng, n, blocks):
        per_block = rng.standard_normal(blocks.max() + 1)
        return 0.1 * rng.standard_normal(n) + 0.5 * per_block[blocks]
    cover = _coverage(blocky)
    assert cover["laplace"] < 0.6
    assert cover["robust"] >= 0.88


def test_robust_keeps_the_priors_information():
    # With priors far tighter than the data, both posteriors are the prior's width.
    rng = np.random.default_rng(1)
    x = rng.standard_normal(500)
    y = 2.0 * x + rng.standard_normal(500)
    blocks = np.arange(500) // 25
    _, laplace, robust = _fit(y, x, blocks, prior_std=1e-4)
    assert np.isclose(laplace, 1e-4, rtol=0.05)
    assert np.isclose(robust, 1e-4, rtol=0.05)
