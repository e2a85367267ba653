"""The diagnosis' kinematics: the speed and acceleration it derives from the
encoders are the derivatives of the smoothed angle, so that an equation of
motion holds between smoothed signals exactly as between true ones."""
import numpy as np
import pytest

from hdjoint.io.recording import Recording
from hdjoint.diagnosis.model.kinematics import gaussian_kernels, kinematics


@pytest.mark.parametrize("sigma", [2.5, 6.0, 11.3])
def test_kernels_are_exact_on_cubics(sigma):
    from scipy.ndimage import convolve1d
    g, d1, d2 = gaussian_kernels(sigma)
    n = np.arange(400.0)
    mid = 200
    assert convolve1d(n, d1)[mid] == pytest.approx(1.0, rel=1e-12)
    assert convolve1d(n ** 2 / 2, d2)[mid] == pytest.approx(1.0, rel=1e-12)
    assert convolve1d(n ** 3 / 6, d2)[mid] == pytest.approx(mid, rel=1e-12)
    assert convolve1d(np.ones_like(n), d2)[mid] == pytest.approx(0.0, abs=1e-12)


@pytest.mark.parametrize("hz", [0.5, 4.0, 20.0])
def test_acceleration_is_the_smoothed_acceleration(hz):
    """Up to the joint's torsional band (tens of Hz): the acceleration of the
    smoothed angle equals the smoothed true acceleration, to 0.5 %."""
    t = np.arange(0, 3.0, 1e-3)
    w = 2 * np.pi * hz
    theta = np.sin(w * t) + 0.3 * t ** 2
    rec = Recording(time=t, i_m=np.zeros_like(t), theta_m=theta, theta_l=theta)
    kin = kinematics(rec)
    true_alpha = -w ** 2 * np.sin(w * t) + 0.6
    smoothed = kin.smooth(true_alpha)
    inside = kin.valid
    assert inside.mean() > 0.9 and not inside[0] and not inside[-1]
    scale = np.max(np.abs(smoothed[inside]))
    assert np.max(np.abs(kin.alpha_m[inside] - smoothed[inside])) < 5e-3 * scale
    speed = kin.smooth(w * np.cos(w * t) + 0.6 * t)
    assert np.max(np.abs(kin.omega_m[inside] - speed[inside])) < 5e-3 * np.max(np.abs(speed))


def test_irregular_sampling_is_handled():
    rng = np.random.default_rng(3)
    t = np.cumsum(rng.uniform(3.5e-3, 4.5e-3, 1500))  # LARA8-like: about 4 ms, irregular
    theta = np.sin(2 * np.pi * 0.5 * t)
    kin = kinematics(Recording(time=t, i_m=np.zeros_like(t), theta_m=theta, theta_l=theta))
    expected = kin.smooth(2 * np.pi * 0.5 * np.cos(2 * np.pi * 0.5 * t))
    assert np.max(np.abs(kin.omega_m - expected)[kin.valid]) < 1e-3
