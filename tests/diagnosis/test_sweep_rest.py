"""The motor at rest on a sweep with dwells (motor_rest.py): static
friction holds there what no speed law can say, and the motor channel does
not compare it."""
import numpy as np
import pytest

from hdjoint.diagnosis.fit.nominal_calibration import calibrate
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint.diagnosis.search.hypothesis_search import HypothesisSearch
from hdjoint.diagnosis.model.motor_rest import motor_at_rest
from hdjoint.io.recording import Recording
from hdjoint.diagnosis.model.kinematics import kinematics
from hdjoint_truth.cases import CONTROL_CASES, draw, record
from hdjoint_truth.excitations import multisine, paper, sweep

N = 100.0
COUNT = 2 * np.pi / 4096  # the motor encoder's step


def _rest_of(excitation, seconds=12.0, scale=1.0):
    t = np.arange(0.0, seconds, 1e-3)
    theta_l = excitation(t, scale)[0]
    theta_m = np.round(N * theta_l / COUNT) * COUNT
    rec = Recording(time=t, i_m=np.zeros_like(t), theta_m=theta_m, theta_l=theta_l, tau_sensor=None, extra={},
                    path=None)
    return t, motor_at_rest(kinematics(rec), t)


def test_the_dwells_of_a_sweep_are_rest_and_its_moves_are_not():
    t, rest = _rest_of(sweep, seconds=30.0)
    dwell = ((t % 4.5) > 3.1) & ((t % 4.5) < 4.4)   # the 1.5 s dwells, inside their edges
    moving = ((t % 4.5) > 0.5) & ((t % 4.5) < 2.5)
    assert rest[dwell].all()
    assert not rest[moving].any()
    # The 30 s sweep ends as its last move stops: slow for less than REST_FOR, cut by the end.
    assert rest[-40:].all()


def test_a_slow_swing_through_zero_speed_is_not_rest():
    # The paper excitation at its smallest amplitude (0.05 rad at 0.25 Hz) reverses every 2 s.
    _, rest = _rest_of(paper, scale=0.85)
    assert not rest[200:].any()


def test_the_start_from_rest_is_compared():
    # A multisine leaves rest over its first 0.16 s: the motor breaks away
    # there. Masked as a rest, the sharp-Coulomb multisine control and the
    # time-delay closure said stribeck_friction (p 4e-4, 9e-4; commit a8c8070).
    t, rest = _rest_of(multisine, seconds=30.0)
    assert not rest[t < 1.0].any()


@pytest.mark.slow
def test_a_lugre_sweep_control_calibrates_jm_and_kt_near_the_truth():
    """Control on a sweep, seed 2: LuGre friction holds +-Fc through every
    dwell. Comparing the motor there took Jm to 2.86x and Kt to 0.74x its
    nominal value (18.6 and -5.2 tolerances); the truth is 0.93x and 0.99x."""
    joint = draw(next(c for c in CONTROL_CASES if c.excitation == "sweep"), 2)
    assert joint.form.friction == "lugre"
    calibrated = calibrate(prepare(record(joint, 0), joint.nominal, workers=1))
    p, diag = calibrated.params, calibrated.objective
    for name in ("Jm", "Kt"):
        off = (p[name] - joint.truth[name]) / diag.priors[name].std
        assert abs(off) < 2.0, (name, p[name] / joint.nominal[name], joint.truth[name] / joint.nominal[name])


@pytest.mark.slow
def test_cogging_is_tested_and_accepted_on_the_sweep_with_dwells():
    """Seed 2's cogging case (order 6 of the motor angle, first recording a
    sweep), where many held-out folds rest. Counted as folds, they would
    zero the z of every motor-angle order (structure.relative_fold_gains)."""
    from hdjoint.diagnosis.effects import EFFECTS
    from hdjoint_truth.cases import EFFECT_CASES
    joint = draw(next(c for c in EFFECT_CASES if c.name == "cogging"), 2)
    assert joint.setups[0].excitation == "sweep" and joint.truth["cog_order"] == 6.0
    calibrated = calibrate(prepare(record(joint, 0), joint.nominal, workers=1))
    p = calibrated.params
    h = HypothesisSearch(calibrated.objective, calibrated.current_alignment).test_alone(EFFECTS["cogging"], p)
    assert h is not None and [o.order for o in h.orders] == [6.0]
    assert h.accepted() and h.gain.folds_compared < 20
