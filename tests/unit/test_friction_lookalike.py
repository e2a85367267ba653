"""Stribeck or Coulomb friction of another shape near zero speed
(friction_lookalike.py): Stribeck is told apart only by held-out gain where
the speed is held in its range, not by gain where the speed passes through zero."""
import numpy as np

from hdjoint.diagnosis.effects.stribeck_friction import HELD_FOR, held_speed, steady_evidence
from hdjoint.diagnosis.model.kinematics import Kinematics

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


def _peak_over_fc(fitted: dict) -> float:
    """The fitted law's largest friction over speed (the C++ law), in units of Fc."""
    from hdjoint.io import parameters
    from hdjoint.diagnosis.model.torque_estimates import motor_friction
    p = dict(parameters.defaults(), Bm=0.0, **fitted)
    speed = np.geomspace(1e-4, 50.0, 4000)
    return float(np.max(motor_friction(p, speed, 0.0 * speed)) / p["Fc"])


def test_a_rise_inside_the_coulomb_switch_is_no_stribeck_rise():
    from hdjoint.diagnosis.effects import EFFECTS
    degenerate = EFFECTS["stribeck_friction"].degenerate
    # The fit on the independent truth's tanh joint (smoothing 0.115 rad/s, no
    # Stribeck): twice Fc, but inside the switch, so the law never exceeds Fc.
    inside = {"Fc": 0.0157, "Fs": 0.031, "omega_s": 0.19, "omega_fc": 0.396}
    assert _peak_over_fc(inside) <= 1.0 + 1e-9
    assert "inside the Coulomb law's own switch" in degenerate(inside, 0.0)
    # A LuGre control's spike at 4 mrad/s is inside the switch too.
    assert degenerate({"Fs": 4.1, "omega_s": 0.0038, "omega_fc": 0.22}, 0.0)
    # A Stribeck rise as the truth plants it (omega_s ~ 8 rad/s) stands above Fc and is one.
    rise = {"Fc": 0.015, "Fs": 0.01, "omega_s": 8.0, "omega_fc": 0.3}
    assert _peak_over_fc(rise) > 1.5
    assert degenerate(rise, 0.0) is None
