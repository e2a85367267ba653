"""The sensors' noise the verdict's floor is built from (diagnosis/verdict/floors.py):
measured in a recording's own high-frequency band or at standstill, where
motion and load changes only add to it."""
import numpy as np
import pytest

from hdjoint.diagnosis.verdict.floors import high_band_noise, measured_noise, standstill_noise


def test_the_high_band_gives_a_white_noise_under_a_slow_motion_and_a_few_spikes():
    rng = np.random.default_rng(3)
    t = np.arange(20000) * 1e-3
    noise = 0.02 * rng.standard_normal(len(t))
    x = 5.0 * np.sin(2 * np.pi * 0.7 * t) + np.where(t > 10.0, 3.0, 0.0) + noise  # a motion and a load step
    x[::997] += 50.0  # wild samples
    assert high_band_noise(x) == pytest.approx(0.02, rel=0.08)
    # The residual's own RMS, what the fit's noise is, would be the motion's: 3.9, not 0.02.
    assert np.sqrt(np.mean((x - x.mean()) ** 2)) > 100 * high_band_noise(x)


def test_a_standstill_gives_the_scatter_about_each_rest_and_the_smaller_estimate_is_taken():
    rng = np.random.default_rng(4)
    x = np.concatenate([np.full(400, 1.0), np.linspace(1.0, 9.0, 200) ** 2, np.full(400, -2.0)])
    x = x + 0.01 * rng.standard_normal(len(x))
    still = np.zeros(len(x), bool)
    still[:400] = still[600:] = True
    assert standstill_noise(x, still) == pytest.approx(0.01, rel=0.15)
    assert standstill_noise(x, np.zeros(len(x), bool)) is None
    value, source = measured_noise(x, still, None)
    assert value == pytest.approx(0.01, rel=0.15) and source in ("standstill", "high-frequency band")
    assert measured_noise(x, still, 0.5) == (0.5, "stated")
