"""Stribeck friction or Coulomb friction of another shape, on the
independent truth: a multisine control whose truth has no Stribeck rise but
LuGre bristles (omega_fc 0.19 rad/s). A Stribeck fit explains 19 % of its
held-out motor residual (p = 0.002) with omega_s = 0.004 rad/s, inside the
Coulomb law's own smoothing (omega_fc = 0.22): a law that only reshapes the
switch through zero speed. It was once named Stribeck (`added`), then "Stribeck
or Coulomb of another shape" (`ambiguous`, still an alarm on a control); now
the fit is degenerate (effects.py, `_rise_inside_the_switch`) and the
recording says what it cannot tell."""
import pytest

from hdjoint.diagnosis.pipeline import diagnose
from hdjoint_truth.cases import CONTROL_CASES, draw, record

pytestmark = pytest.mark.slow


def test_a_lugre_controls_zero_speed_spike_is_no_stribeck():
    joint = draw(next(c for c in CONTROL_CASES if c.excitation == "chirp"), 1)
    assert joint.form.friction == "lugre" and joint.setups[1].excitation == "multisine" and not joint.truth["Fs"]
    _, doc = diagnose(record(joint, 1), joint.nominal)
    assert doc["verdict"] == "consistent", (doc["findings"], doc["unexplained"])
    tried = {h["effect"]: h for h in doc["hypotheses_tested"][0]}["stribeck_friction"]
    assert tried["held_out_gain"] > 0.1 and "inside the Coulomb law's own switch" in tried["degenerate"]
    said = [c for c in doc["cannot_tell"] if c.get("effect") == "stribeck_friction"]
    assert said and "not the effect" in said[0]["why"] and "0.5-20 rad/s" in said[0]["record"], doc["cannot_tell"]


def test_a_real_stribeck_rise_is_still_named_on_a_multisine():
    # The truth's rise (Fs ~ 0.01 N.m over ~8 rad/s) lies far outside the
    # Coulomb switch; the multisine never holds a slow speed, so it is named
    # in the look-alike set with the excitation that would separate the two.
    from hdjoint_truth.cases import EFFECT_CASES
    joint = draw(next(c for c in EFFECT_CASES if c.name == "stribeck friction"), 1)
    assert joint.setups[0].excitation == "multisine" and joint.truth["omega_s"] > 1.0
    _, doc = diagnose(record(joint, 0), joint.nominal)
    first = doc["findings"][0]
    assert first["effect"] == "stribeck_friction", doc["findings"]
    assert first["parameters"]["omega_s"] > doc["params"]["omega_fc"]
    if first["kind"] == "ambiguous":
        assert [a["effect"] for a in first["alternatives"]] == ["stribeck_friction", "coulomb_friction"]
        assert "0.5-20 rad/s" in first["separate_by"]
