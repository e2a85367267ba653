"""How large an effect a recording would show (detection_limit.py), on the
independent truth's wave-generator compliance (seed 0, paper run). At the
truth's size (Kw 38, Cw 8) it is a 2.5 % softer flexspline over the +-4.4
N.m recorded, and the diagnosis rightly says `consistent`; it must also say
that a compliance as large as the parameter table's joint (Kw 10) would not
have shown, and from what size it would. The limit must mean what it says:
the same joint with the compliance twice the limit's size is named."""
import pytest

from hdjoint_truth.cases import EFFECT_CASES, draw, record
from hdjoint.diagnosis.pipeline import diagnose

pytestmark = pytest.mark.slow

CASE = next(c for c in EFFECT_CASES if c.name == "wave generator compliance")


def _limit(doc, effect):
    return next(x for x in doc["detection_limits"] if x["effect"] == effect)


def test_a_compliance_too_small_to_show_is_said_and_one_past_the_limit_is_named():
    joint = draw(CASE, 0)
    _, doc = diagnose(record(joint, 0), joint.nominal)
    assert doc["verdict"] == "consistent", doc["findings"]
    limit = _limit(doc, "wave_generator_compliance")
    assert limit["parameter"] == "Kw" and limit["reference"] == 10.0
    # A stiffer bearing twists less: the truth's Kw lies beyond the limit, hidden.
    assert 1.0 < limit["limit"] < joint.truth["Kw"]
    said = next(x for x in doc["cannot_tell"] if x.get("effect") == "wave_generator_compliance")
    assert "would not show" in said["why"] and f"Kw of {limit['limit']:.3g} N.m/rad" in said["why"]
    assert said["record"] and "wave_generator_compliance" in doc["verdict_note"]

    joint.truth["Kw"] = limit["limit"] / 2.0  # twice the compliance the recording would just show
    _, past = diagnose(record(joint, 0), joint.nominal)
    named = [f["effect"] for f in past["findings"]] + [a["effect"] for f in past["findings"]
                                                       for a in f.get("alternatives") or []]
    assert "wave_generator_compliance" in named, past["findings"]
