"""The diagnosis on concealed effects (hdjoint.fmu.concealed_effects, 20 s recordings):
controls stay consistent, and the effects it finds are found in the right
part of the model with the fit improving on held-out data.

The full benchmark (every effect ID, 30 s recordings) is
benchmarks/diagnosis_suite.py; its table, including the two effects it
does not name (absorbed by a look-alike's calibration), is in the README."""
import pytest

from hdjoint.fmu.concealed_effects import CASES, Case, nominal_for, record
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.diagnosis.effects import EFFECTS

pytestmark = pytest.mark.slow  # a diagnosis of a 20-30 s recording per case

DURATION = 20.0


def _run(name_start, duration=DURATION):
    case = next(c for c in CASES if c.name.startswith(name_start))
    return case, diagnose(record(case, duration), nominal_for(case))[1]


@pytest.mark.parametrize("name", ["control A", "control B"])
def test_controls_are_consistent(name):
    _, doc = _run(name)
    assert doc["verdict"] == "consistent" and doc["findings"] == [] and doc["unexplained"] == []


@pytest.mark.parametrize("name,effect,duration", [
    ("kinematic error", "kinematic_error", DURATION),
    ("wave generator load", "wave_generator_load", DURATION),
    ("cogging", "cogging", DURATION),
    ("link friction", "link_friction", DURATION),
    ("backlash", "backlash", DURATION),
    ("viscous friction", "viscous_friction", DURATION),
    # The drift's gain is uneven over the folds: a drift is judged by its
    # pooled held-out gain against the simulated null (Effect.uneven_over_folds).
    ("thermal drift", "thermal_drift", DURATION),
    # These three need the benchmark's 30 s: at 20 s their held-out gain
    # is not yet significant fold by fold (the verdict is then consistent).
    # The Bouc-Wen loop is named once the Dahl loop's slow drive is the
    # link's torque (part_torques._slow_torsion_from_link): driven by the
    # encoders' torsion alone it made the low-torque folds worse.
    ("hysteresis", "hysteresis", 30.0),
    ("Stribeck friction", "stribeck_friction", 30.0),
    ("time delay", "time_delay", 30.0),
])
def test_effect_is_named_located_and_improves_held_out_fit(name, effect, duration):
    case, doc = _run(name, duration)
    assert doc["verdict"] == "missing_physics"
    first = doc["findings"][0]
    assert first["effect"] == effect
    assert first["where"]["part"] == EFFECTS[effect].part
    assert first["fit"]["holdout_rms_after"] < first["fit"]["holdout_rms_before"]
    assert first["confidence"] > 0.5


def test_coulomb_friction_is_found_as_motor_friction():
    """LuGre truth without Coulomb friction in the nominal model: named as
    Coulomb or its look-alike Stribeck, in the motor."""
    _, doc = _run("Coulomb friction")
    assert doc["findings"] and doc["findings"][0]["effect"] in ("coulomb_friction", "stribeck_friction")
    assert doc["findings"][0]["where"]["part"] == "motor"


def test_torque_constant_warm_up_is_named_with_its_size():
    """The Kt form of thermal_drift, at the independent truth's size (-4 %
    with a 15 s time constant), on a 20 s recording: named in the motor, its
    Kt_warmup interval holding the truth and excluding zero. (The law is the
    hypothesis's own: this checks the chain FMU -> recording -> fit, and the
    pooled-gain test of a drift; hdjoint_truth checks an independent one.)"""
    case = Case("thermal drift of Kt", ("thermal_drift",), truth={"Kt_warmup": -0.04, "Kt_warmup_tc": 15.0})
    doc = diagnose(record(case, DURATION), nominal_for(case))[1]
    assert doc["verdict"] == "missing_physics"
    first = doc["findings"][0]
    assert first["effect"] == "thermal_drift" and first["where"]["part"] == "motor"
    lo, hi = first["intervals"]["Kt_warmup"]
    assert lo <= -0.04 <= hi and hi < 0.0
    assert first["confidence"] > 0.5
