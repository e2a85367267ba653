"""Model-form factors: intervals widened by how much the raw posterior
underestimated the error on joints of another model form (fitted on some
seeds of the independent truth, benchmarks/interval_coverage.py)."""
import json
import sys
from pathlib import Path

import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import interval_coverage as coverage  # noqa: E402

from hdjoint.diagnosis.fit import priors as calibration  # noqa: E402
from hdjoint.io import parameters
from hdjoint.diagnosis.fit.priors import Calibrated, Prior  # noqa: E402


def _rows(name, errors, std):
    return [{"name": name, "kind": "paper", "seed": 0, "error": float(e), "raw": std} for e in errors]


def test_a_factor_makes_the_interval_cover_errors_the_raw_std_underestimates():
    rng = np.random.default_rng(3)
    biased = _rows("Fc", 3.0 * rng.standard_normal(400), 1.0)   # errors 3x what the posterior says
    honest = _rows("Kf", 0.8 * rng.standard_normal(400), 1.0)   # the posterior is already wide enough
    factors = coverage.fit_factors(biased + honest)
    assert 2.6 < factors["Fc"] < 3.4
    assert factors["Kf"] == 1.0  # never narrower than the posterior
    fresh = 3.0 * rng.standard_normal(4000)
    assert 0.93 < np.mean(np.abs(fresh) <= coverage.Z95 * factors["Fc"]) < 0.97


def test_the_shipped_factors_say_where_they_were_measured_and_widen_the_reported_interval():
    stored = json.loads(calibration.MODEL_FORM_FACTORS.read_text())
    assert stored["measured"]["recordings"] >= 40 and stored["measured"]["by"].startswith("python benchmarks/")
    factors = calibration.model_form_factors()
    assert factors and all(f >= 1.0 for f in factors.values())
    name, factor = max(factors.items(), key=lambda kv: kv[1])
    assert factor > 1.0
    value = parameters.table()[name].default or 1.0
    std = 1e-6 * abs(value)  # far inside the parameter's range: no clipping
    c = Calibrated(name, value, value, calibration.widened(name, std), Prior(value, abs(value)))
    half = 1.959964 * std * factor
    assert c.interval == pytest.approx((value - half, value + half), rel=1e-12)
    assert f"{factor:.2f}" in c.as_dict()["interval"]
