"""Stribeck or Coulomb friction of another shape near zero speed
(friction_lookalike.py): Stribeck is told apart only by held-out gain where
the speed is held in its range, not by gain where the speed passes through zero."""
import numpy as np

from hdjoint.friction_lookalike import HELD_FOR, held_speed, steady_evidence
from hdjoint.signals import Kinematics

STEP = 1e-3
TIME = np.arange(0.0, 20.0, STEP)
FOLD = (np.arange(len(TIME)) * 40 // len(TIME)).astype(int)
TEST = FOLD % 2 == 1


def _kinematics(omega):
    return Kinematics(omega_m=omega, alpha_m=np.gradient(omega, STEP), omega_l=omega / 100, alpha_l=0 * omega,
                      valid=np.ones(len(omega), bool), smooth=None)


def _plateaus():
    """Held speeds of +-5 rad/s for 0.5 s, joined by 0.1 s ramps through zero."""
    phase = np.mod(TIME, 1.2)
    level = np.where(np.mod(TIME // 1.2, 2) == 0, 5.0, -5.0)
    ramp = np.clip(phase / 0.1, 0.0, 1.0)
    previous = -level
    return previous + (level - previous) * ramp


def test_held_speeds_are_the_plateaus_after_their_first_tenth_of_a_second():
    omega = _plateaus()
    held = held_speed(_kinematics(omega), TIME)
    phase = np.mod(TIME, 1.2)
    assert not held[(phase < 0.1)].any()  # the ramps through zero
    # a plateau counts once the last reversal (mid-ramp) is HELD_FOR behind
    assert held[(phase > 0.05 + HELD_FOR + 0.01) & (phase < 1.19)].all()


def test_gain_at_held_speeds_separates_gain_at_passages_does_not():
    omega = _plateaus()
    held = held_speed(_kinematics(omega), TIME)
    rng = np.random.default_rng(0)
    noise = rng.normal(size=len(TIME)) ** 2
    structure = np.where(held, 1.0, 0.0)
    # A hypothesis that explains structure at held speeds (a Stribeck rise)...
    steady = steady_evidence(noise + structure, noise, held, FOLD, TEST)
    assert steady.separates and steady.steady_share > 0.9
    # ... and one that explains the same amount only where the speed passes through zero.
    passing = np.where(~held, 3.0, 0.0)
    transient = steady_evidence(noise + passing, noise + 0.0 * passing, held, FOLD, TEST)
    assert not transient.separates and transient.steady_share < 0.05


def test_too_few_held_folds_cannot_separate():
    omega = 20.0 * np.sin(2 * np.pi * 3.0 * TIME)  # never held
    held = held_speed(_kinematics(omega), TIME)
    e = steady_evidence(np.ones(len(TIME)) * 2, np.ones(len(TIME)), held, FOLD, TEST)
    assert not e.separates and np.isnan(e.z)
