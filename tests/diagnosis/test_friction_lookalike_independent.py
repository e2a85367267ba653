"""Stribeck friction or Coulomb friction of another shape, on the
independent truth: a multisine control whose truth has no Stribeck rise but
LuGre bristles (omega_fc 0.19 rad/s). A Stribeck fit explains 19 % of its
held-out motor residual (p = 0.002) with omega_s = 0.004 rad/s, i.e. inside
the Coulomb law's own smoothing; the multisine never holds a slow speed, so
the recording cannot tell the two apart. It used to name Stribeck
(`added`): now one ambiguous finding with both and the excitation that
separates them (friction_lookalike.py)."""
import pytest

from hdjoint.diagnosis import diagnose
from hdjoint.truth.cases import CONTROL_CASES, draw, record

pytestmark = pytest.mark.slow


def test_a_lugre_truth_on_a_multisine_is_stribeck_or_coulomb_smoothing_not_a_confident_stribeck():
    joint = draw(next(c for c in CONTROL_CASES if c.excitation == "chirp"), 1)
    assert joint.form.friction == "lugre" and joint.setups[1].excitation == "multisine" and not joint.truth["Fs"]
    _, doc = diagnose(record(joint, 1), joint.nominal)
    friction = [f for f in doc["findings"] if "stribeck_friction" in (f["effect"], *(
        a["effect"] for a in f.get("alternatives", [])))]
    assert friction, doc["findings"]
    f = friction[0]
    assert f["kind"] == "ambiguous"
    assert [a["effect"] for a in f["alternatives"]] == ["stribeck_friction", "coulomb_friction"]
    shares = [a["evidence_share"] for a in f["alternatives"]]
    assert sum(shares) == pytest.approx(1.0, abs=0.01) and min(shares) > 0.3  # neither side is confident
    held = f["evidence"]["at_held_slow_speeds"]
    assert held["tells_apart_from_smoothing"] is False and held["share_of_the_gain"] < 0.2
    assert "held" in f["separate_by"] and "0.5-20 rad/s" in f["separate_by"]
