"""The open-library fallback proposes terms outside the named effect library
(position-dependent friction, a kinematic error modulated by torque) with a
positive held-out gain, and proposes nothing on a joint that matches its model."""
import pytest

from hdjoint.io import parameters
from hdjoint.diagnosis.model.current_alignment import align_current
from hdjoint.diagnosis.fit.objective import Objective
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint.diagnosis.verdict.open_library import propose_terms
from hdjoint_truth.physics import Form
from hdjoint_truth.simulate import Setup, simulate

NOMINAL = dict(parameters.defaults(), wg_load=1.0)
EVERY_CHANNEL = [{"channel": name} for name in ("transmission", "motor", "link")]


def diagnosis_of(form: Form) -> Objective:
    """A short recording of the independent truth with `form`, otherwise the
    nominal joint, its current aligned with the encoders as calibration does
    before any term is proposed (the truth's drive holds its current over a
    sample: unaligned, that reads as N*Kt/2*(i_m[t-1] - i_m))."""
    rec = simulate(dict(NOMINAL, Df=4.0), form, Setup(excitation="multisine", duration=8.0, seed=3), NOMINAL)
    diag = Objective(prepare(rec, NOMINAL))
    align_current(diag, NOMINAL)
    return diag


def proposals(form: Form) -> dict[str, dict]:
    diag = diagnosis_of(form)
    return {p["channel"]: p for p in propose_terms(diag, diag.nominal, EVERY_CHANNEL)}


@pytest.mark.slow
def test_position_dependent_friction_is_proposed_in_the_motor_channel():
    found = proposals(Form(friction_ripple=(3.0, 0.5)))
    motor = found["motor"]
    assert next(iter(motor["coefficients"])) == "sign(omega_m)*cos(3*theta_m)"
    assert motor["holdout_gain"] > 0.1
    # Its size: N * Fc * 0.5 of link torque, the sign of a motor-side torque in the motor channel.
    coefficient = motor["coefficients"]["sign(omega_m)*cos(3*theta_m)"]
    assert coefficient == pytest.approx(-NOMINAL["N"] * NOMINAL["Fc"] * 0.5, rel=0.25)


@pytest.mark.slow
def test_kinematic_error_modulated_by_torque_is_proposed_in_the_transmission_channel():
    found = proposals(Form(kinematic_torque=(3.0, 4e-6)))
    transmission = found["transmission"]
    assert "tau*cos(3*theta_m)" in transmission["coefficients"]
    assert transmission["holdout_gain"] > 0.05


@pytest.mark.slow
def test_nothing_is_proposed_where_the_model_holds_or_nothing_is_unexplained():
    diag = diagnosis_of(Form())
    assert propose_terms(diag, diag.nominal, EVERY_CHANNEL) == []
    assert propose_terms(diag, diag.nominal, []) == []
