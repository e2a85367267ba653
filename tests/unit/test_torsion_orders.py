"""The kinematic error's orders on the encoders' torsion (torsion_orders.py):
a ripple at a motor order is found under the nuisances every recording has
(encoder zero, the load's twist, a link-angle trend), with its amplitude
inside its interval; coloured noise alone names no order."""
import numpy as np
import pytest

from hdjoint.diagnosis.model.kinematics import folds
from hdjoint.diagnosis.search.torsion_orders import fit_orders, nuisances, order_evidence

N = 2000
ORDERS = [k / 2 for k in range(1, 13)]


def _jog(seed: int, ripple: float):
    """A 4 s jog over 7.7 motor revolutions: torsion = zero + twist + trend + ripple + coloured noise."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 4.0, N)
    theta_m = 7.7 * 2 * np.pi * (t / 4.0 - np.sin(2 * np.pi * t / 4.0) / (2 * np.pi))
    theta_l = theta_m / 121
    torque = 120 + 40 * np.sin(theta_l * 8) + 5 * rng.standard_normal(N)
    noise = np.convolve(rng.standard_normal(N), np.ones(15) / 15, mode="same") * 2e-5
    torsion = 3e-3 + torque / 31000 + 2e-4 * theta_l + ripple * np.cos(2 * theta_m - 0.4) + noise
    return torsion, nuisances(torque, theta_l), theta_m


def test_a_ripple_under_the_nuisances_is_named_with_its_amplitude():
    torsion, x, theta_m = _jog(0, 6e-5)
    fold = folds(N, 20)
    found = order_evidence(torsion, x, theta_m, ORDERS, fold, fold % 2 == 0, fold % 2 == 1)
    named = [o for o in found if o.p_value <= 0.05 and o.gain.z > 3 and o.gain.gain > 0.003]
    assert [o.order for o in named] == [2.0]
    two = named[0]
    assert abs(two.amplitude - 6e-5) < two.half_width and two.half_width < 2e-5
    joint = fit_orders(torsion, x, [(theta_m, 2.0)], fold, fold % 2 == 0, fold % 2 == 1)
    assert joint.coefficients[0] == pytest.approx((6e-5 * np.cos(0.4), 6e-5 * np.sin(0.4)), abs=1e-5)
    assert joint.mse_after < 0.5 * joint.mse_before and joint.gain.gain > 0.5


@pytest.mark.parametrize("seed", range(5))
def test_coloured_noise_names_no_order(seed):
    torsion, x, theta_m = _jog(seed, 0.0)
    fold = folds(N, 20)
    found = order_evidence(torsion, x, theta_m, ORDERS, fold, fold % 2 == 0, fold % 2 == 1)
    assert not [o for o in found if o.p_value <= 0.05 and o.gain.z > 3 and o.gain.gain > 0.003]
