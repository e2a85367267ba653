"""A new effect is one file: an Effect defined here, in the test alone, is
found by the diagnosis, fitted, tested and named end to end on a recording
where it is planted. The library's own viscous friction is taken out for
the test, so the parameter the new effect fits (Bm) reaches the estimates'
cache keys only through the new definition: a hand-kept key, or an engine
that named effects, would miss it."""
import pytest

from hdjoint.diagnosis import effects
from hdjoint.diagnosis.effects import EFFECTS, Effect, Size, part_parameters
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.fmu.concealed_effects import CASES, nominal_for, record

pytestmark = pytest.mark.slow

DAMPING = Effect(
    "motor_damping", "motor", ("Bm",),
    "damping of the motor proportional to its speed (bearing and seal drag)", "Bm*omega_m",
    switched_by=("Bm",), starts=({"Bm": 3e-5}, {"Bm": 2e-4}), needs=("speed",),
    revealed_by="constant high speeds in both directions", resizes=("Bm",), in_friction_law=True,
    size=Size("Bm", source="a test's own effect"))


@pytest.fixture
def library_with_the_new_effect():
    library = dict(EFFECTS)
    effects.unregister("viscous_friction")
    effects.register(DAMPING)
    yield
    EFFECTS.clear()
    EFFECTS.update(library)


def test_registering_an_effect_puts_its_parameters_in_the_cache_keys(library_with_the_new_effect):
    assert "motor_damping" in EFFECTS and "viscous_friction" not in EFFECTS
    assert "Bm" in part_parameters("motor") and "Bm" in effects.friction_law_parameters()


def test_a_registered_effect_is_named_end_to_end(library_with_the_new_effect):
    case = next(c for c in CASES if c.present == ("viscous_friction",))
    _, doc = diagnose(record(case, 30.0), nominal_for(case))
    assert doc["verdict"] == "missing_physics"
    first = doc["findings"][0]
    assert first["effect"] == "motor_damping", doc["findings"]
    assert first["parameters"]["Bm"] == pytest.approx(1.5e-4, rel=0.3)  # the planted value
