"""The motor equation's current is the smoothing filter's derivative of the
charge (channels.current_charge): a current that alternates from sample to
sample, logged at jittered time stamps, must not alias into the band the
filter passes. The independent truth's speed loop does exactly that on its
sweeps, and an aliased alternation would read as a current delay."""
import numpy as np
import pytest

from hdjoint.diagnosis.model.torque_estimates import Prepared, _smoothed_current
from hdjoint.io.recording import Recording
from hdjoint.diagnosis.model.kinematics import kinematics

TS, SUBSTEP = 1e-3, 1.25e-4


def _rotor(late: np.ndarray, current: np.ndarray) -> Prepared:
    """A unit-inertia rotor under the current held over each sample period
    (from the nominal instant), its angle read `late` after that instant and
    stamped at the instant it was read."""
    n = len(current)
    grid = np.arange(n) * TS
    omega = np.concatenate([[0.0], np.cumsum(current * TS)])[:-1]
    theta = np.concatenate([[0.0], np.cumsum(omega * TS + 0.5 * current * TS ** 2)])[:-1]
    stamps = grid + late
    theta = theta + omega * late + 0.5 * current * late ** 2
    rec = Recording(time=stamps, i_m=current, theta_m=theta, theta_l=theta)
    prep = Prepared(rec, kinematics(rec), stamps - stamps[0])
    prep.current_shift = -TS / 2  # held over the following sample
    return prep


def _slow(n: int) -> np.ndarray:
    t = np.arange(n) * TS
    return 0.6 * np.sin(2 * np.pi * 1.5 * t) + 0.2 * np.sin(2 * np.pi * 11 * t)


def _mismatch(prep: Prepared) -> float:
    """RMS of (smoothed current - acceleration) relative to the acceleration's peak."""
    ok = prep.kin.valid
    a = prep.kin.alpha_m
    return float(np.sqrt(np.mean((_smoothed_current(prep, 0.0) - a)[ok] ** 2)) / np.max(np.abs(a[ok])))


def test_an_alternating_current_at_jittered_stamps_is_not_aliased():
    """The loop's alternation (0.25 A) with stamps late more often on even
    samples: interpolating the samples onto the filter's grid left 2.5 % of
    the peak acceleration as error; the charge leaves under 0.3 %."""
    n = 6000
    rng = np.random.default_rng(3)
    late = np.where(rng.random(n) < np.where(np.arange(n) % 2 == 0, 0.8, 0.2), SUBSTEP, 0.0)
    current = _slow(n) + 0.25 * (-1.0) ** np.arange(n)
    assert _mismatch(_rotor(late, current)) < 3e-3


@pytest.mark.parametrize("shift", [0.0, -TS / 4, -TS / 2])
def test_the_charge_is_the_smoothed_current_where_the_current_is_smooth(shift):
    """Uniform stamps, a smooth current: d/dt of the smoothed charge is the
    smoothed, shifted current (what the motor equation read before)."""
    n = 4000
    prep = _rotor(np.zeros(n), _slow(n))
    prep.current_shift = shift
    t, i = prep.rec.time, prep.rec.i_m
    expected = prep.kin.smooth(np.interp(t + shift, t, i))
    ok = prep.kin.valid
    assert np.max(np.abs(_smoothed_current(prep, 0.0) - expected)[ok]) < 2e-4 * np.max(np.abs(i))
