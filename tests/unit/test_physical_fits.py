"""A finding whose fitted parameters are not physical is not a finding
(issue 38, goal 5): each effect judges its own fit against the recording's
scale (Effect.degenerate: its torsion and length)."""

from hdjoint.diagnosis.effects import EFFECTS
from hdjoint.diagnosis.effects.base import RecordingScale
from hdjoint.io import parameters

SCALE = RecordingScale(torsion_span=2e-3, duration=30.0)
THERMAL = EFFECTS["thermal_drift"]


def thermal(**fitted) -> dict:
    return dict(parameters.defaults(), **{"Kt_warmup": 0.0, "Kt_warmup_tc": 15.0, "Fc_drift": 0.0, **fitted})


def test_a_warm_up_with_a_seconds_time_constant_is_a_thermal_process():
    assert THERMAL.degenerate(thermal(Kt_warmup=-0.03, Kt_warmup_tc=15.0), SCALE) is None
    assert THERMAL.degenerate(thermal(Fc_drift=-0.02), SCALE) is None


def test_a_kt_step_within_a_fraction_of_a_second_is_not_a_warm_up():
    # The catch-all: Kt -22 % with a 0.1 s time constant on a run whose speed steps up.
    why = THERMAL.degenerate(thermal(Kt_warmup=-0.22, Kt_warmup_tc=0.1), SCALE)
    assert why is not None and "0.1 s time constant" in why and "not a thermal process" in why


def test_a_kt_change_beyond_what_magnets_lose_is_not_a_warm_up():
    why = THERMAL.degenerate(thermal(Kt_warmup=-0.3, Kt_warmup_tc=20.0), SCALE)
    assert why is not None and "-30.0 %" in why


def test_a_time_constant_is_not_read_where_the_kt_term_carries_nothing():
    # A friction drift with the Kt term at zero leaves the time constant unidentified, wherever the fit left it.
    assert THERMAL.degenerate(thermal(Fc_drift=-0.01, Kt_warmup=0.0, Kt_warmup_tc=0.2), SCALE) is None


def test_friction_driven_through_zero_is_not_a_warm_up():
    why = THERMAL.degenerate(thermal(Fc_drift=-0.05), SCALE)  # 1 - 0.05/s * 30 s < 0
    assert why is not None and "through zero" in why
