"""`hdjoint diagnose` and `hdjoint estimate --calibrate-from` start without scipy.stats (its distributions'
docstrings take a third of a second to build) nor matplotlib (imported by
the report's helper while the diagnosis runs): the normal distribution and
Spearman's correlation it uses give scipy.stats's numbers bit for bit."""
import subprocess
import sys

import numpy as np
import pytest
from scipy import stats

from hdjoint.diagnosis import normal
from hdjoint.diagnosis.effects.needs import spearman


def test_diagnose_imports_neither_scipy_stats_nor_matplotlib():
    code = ("import sys; import hdjoint.app.cli, hdjoint.jobs.diagnose, hdjoint.jobs.sensorless_calibration, "
            "hdjoint.diagnosis.pipeline, hdjoint.diagnosis.output.report; print(sorted(m for m in ('scipy.stats', 'matplotlib') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


@pytest.mark.parametrize("name", ["cdf", "sf"])
def test_the_normal_tails_are_scipy_stats(name):
    rng = np.random.default_rng(3)
    x = np.concatenate([rng.normal(scale=s, size=5000) for s in (0.1, 1.0, 8.0, 40.0)]
                       + [[0.0, -0.0, np.inf, -np.inf, np.nan, 1e-300, -39.0]])
    assert np.array_equal(getattr(normal, name)(x), getattr(stats.norm, name)(x), equal_nan=True)
    assert getattr(normal, name)(2.3) == getattr(stats.norm, name)(2.3)


@pytest.mark.parametrize("name", ["ppf", "isf"])
def test_the_normal_quantiles_are_scipy_stats(name):
    q = np.concatenate([np.random.default_rng(4).uniform(size=20000), [0.0, 1.0, 0.5, 1e-300, 0.975, np.nan]])
    assert np.array_equal(getattr(normal, name)(q), getattr(stats.norm, name)(q), equal_nan=True)


def test_spearman_is_scipy_stats_spearmanr():
    rng = np.random.default_rng(5)
    for trial in range(300):
        n = int(rng.integers(3, 300))
        x = np.arange(n, dtype=float) if trial % 2 else rng.integers(0, 6, n).astype(float)  # with ties
        y = rng.normal(size=n) if trial % 3 else np.round(rng.normal(size=n), 1)
        assert spearman(x, y) == stats.spearmanr(x, y)[0]


def test_spearman_of_a_constant_or_nan_sample_is_nan():
    assert np.isnan(spearman(np.arange(5.0), np.ones(5)))
    assert np.isnan(spearman(np.arange(5.0), [1.0, 2.0, np.nan, 3.0, 4.0]))
