"""A long recording is analysed in windows spread over it: the windows
cover the whole run, are filtered and simulated each on its own (never
across the jump to the next), and are the diagnosis' folds."""
import numpy as np
import pytest

from hdjoint.diagnosis.model import prepare as preparing
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.diagnosis.rules import FOLDS
from hdjoint.io import parameters
from hdjoint.fmu.concealed_effects import CASES, nominal_for, record
from hdjoint.diagnosis.model.torque_estimates import Prepared, tau_transmission
from hdjoint.diagnosis.model.kinematics import kinematics, sample_windows, window_labels

pytestmark = pytest.mark.slow  # a long recording diagnosed in windows


@pytest.fixture(scope="module")
def long_rec():
    case = next(c for c in CASES if c.present == ("gravity_load",))
    return case, record(case, duration=24.0)


def test_windows_are_spread_over_the_whole_run(long_rec):
    _, rec = long_rec
    sampled, starts = sample_windows(rec, analysed_seconds=6.0, count=12)
    assert len(starts) == 12 and starts[0] == 0
    assert sampled.duration > 0.9 * rec.duration  # first window at the start, last at the end
    assert abs(len(sampled) - 6.0 / rec.median_step) < 12 * 2
    first_times = sampled.time[starts]
    assert np.allclose(np.diff(first_times), np.diff(first_times).mean(), rtol=0.01)
    whole, one = sample_windows(rec, analysed_seconds=30.0, count=12)
    assert whole is rec and list(one) == [0]


def test_each_window_is_filtered_and_simulated_on_its_own(long_rec):
    _, rec = long_rec
    sampled, starts = sample_windows(rec, analysed_seconds=6.0, count=12)
    kin = kinematics(sampled, starts=starts)
    labels = window_labels(len(sampled), starts)
    p = dict(parameters.defaults(), hys_H=0.2, hys_sigma=2e4)  # stateful: the window's history only
    prep = Prepared(sampled, kin, sampled.time - rec.time[0], starts)
    torque = tau_transmission(prep, p)
    for w in (0, 5, 11):
        piece = sampled.slice(*np.flatnonzero(labels == w)[[0, -1]] + [0, 1])
        alone = kinematics(piece)
        np.testing.assert_allclose(kin.omega_m[labels == w], alone.omega_m, rtol=0, atol=1e-9)
        own = tau_transmission(Prepared(piece, alone, piece.time - rec.time[0]), p)
        np.testing.assert_allclose(torque[labels == w], own, rtol=0, atol=1e-12)


def test_a_long_recording_is_diagnosed_in_windows(long_rec, monkeypatch):
    case, rec = long_rec
    monkeypatch.setattr(preparing, "ANALYSED_SECONDS", 8.0)
    result, doc = diagnose(rec, nominal_for(case))
    diag = result.objective
    assert len(diag.rec) < 0.4 * len(rec)
    assert doc["recording"]["samples"] == len(rec) and doc["recording"]["analysed_samples"] == len(diag.rec)
    # The windows are the folds: each one wholly fitted or wholly held out.
    assert set(np.unique(diag.fold)) == set(range(FOLDS))
    assert doc["verdict"] == "missing_physics" and doc["findings"][0]["effect"] == "gravity_load"
    assert doc["params"]["mgl"] == pytest.approx(5.0, rel=0.1)
