"""A `consistent` verdict says what the recording could not tell
(cannot_tell.py): hypotheses with held-out gain and the training data's
support that the folds do not agree on, and constants of the joint that
calibration moved far beyond their tolerance."""
from types import SimpleNamespace

from hdjoint.diagnosis.fit.priors import Calibrated, Prior
from hdjoint.diagnosis.verdict.cannot_tell import cannot_tell
from hdjoint.diagnosis.verdict.detection_limit import Limit


def _tested(effect, gain, z, dbic, accepted=False, p=0.5):
    return {"effect": effect, "held_out_gain": gain, "z": z, "p_value": p, "delta_bic": dbic, "accepted": accepted}


def _result(last_round, calibration=(), unexplained=(), limits=()):
    return SimpleNamespace(tested=[last_round], unexplained=list(unexplained),
                           calibration={c.name: c for c in calibration}, limits=list(limits))


def test_a_sweeps_coulomb_friction_and_its_absorbed_inertia_are_said():
    # figures shaped like the independent truth's sweep (seed 2) with Coulomb friction missing
    result = _result([_tested("coulomb_friction", 0.2848, -1.24, -12197.2),
                      _tested("backlash", -0.0, 0.71, 9.6)],
                     [Calibrated("Jm", 2.09e-5, 8.39e-5, 1e-6, Prior(2.09e-5, 2.09e-6)),
                      Calibrated("Kt", 0.045, 0.046, 1e-3, Prior(0.045, 0.00225))])
    said = cannot_tell(result)
    assert [x.get("effect") or x["parameter"] for x in said] == ["coulomb_friction", "Jm"]
    assert "constant-speed runs" in said[0]["record"] and "4.01x" in said[1]["why"]


def test_nothing_supported_nothing_moved_nothing_said():
    result = _result([_tested("coulomb_friction", 0.01, 1.0, -50.0), _tested("backlash", 0.2, 1.0, 5.0),
                      _tested("viscous_friction", 0.3, 5.0, -500.0, accepted=True)],
                     # Bm belongs to viscous friction: a resized finding's business, not this list's
                     [Calibrated("Bm", 3e-5, 3e-4, 1e-6, Prior(3e-5, 1.5e-5))])
    assert cannot_tell(result) == []


def test_an_unconfirmed_hypothesis_already_unexplained_is_not_said_twice():
    result = _result([_tested("gravity_load", 0.96, 80.0, -900.0, p=0.36)],
                     unexplained=[{"feature": "what gravity_load would explain (the simulated null cannot confirm it)"}])
    assert cannot_tell(result) == []


def test_a_degenerate_fit_says_it_is_not_the_effect():
    # the LuGre control's multisine (chirp seed 1), as measured: 19 % held out, p = 0.002, inside the switch
    why = "the fitted rise (omega_s = 0.0038 rad/s) lies inside the Coulomb law's own switch"
    h = dict(_tested("stribeck_friction", 0.1917, 3.19, -3524.0, p=0.0019), degenerate=why)
    said = cannot_tell(_result([h]))
    assert [x["effect"] for x in said] == ["stribeck_friction"]
    assert "not the effect: " + why in said[0]["why"] and "fold by fold" not in said[0]["why"]


def _limit(effect, parameter, reference, limit, factor, grows=1.0, source="a catalogue"):
    return Limit(effect, parameter, reference, limit, factor, grows, source)


def test_an_effect_hidden_at_its_sourced_reference_size_is_said_with_its_limit():
    hidden = _limit("wave_generator_compliance", "Kw", 10.0, 5.0, 2.0, grows=-1.0)
    shown = _limit("coulomb_friction", "Fc", 0.015, 0.003, 0.2)
    never = _limit("stiffness_nonlinearity", "Cf", 0.0645, None, None)
    unsourced = _limit("time_delay", "i_delay", 0.001, 0.002, 2.0, source="")
    said = cannot_tell(_result([], limits=[hidden, shown, never, unsourced]))
    assert [x["effect"] for x in said] == ["wave_generator_compliance", "stiffness_nonlinearity"]
    assert "from a wave generator stiffness Kw of 5 N.m/rad (2 times the reference, 10 N.m/rad, a catalogue)" in said[0]["why"]
    assert "not show at any size up to 1024 times" in said[1]["why"]
    assert all(x["record"] for x in said)


def test_an_effect_the_round_saw_is_not_said_again_for_its_limit():
    seen = _tested("wave_generator_compliance", 0.05, 1.0, -50.0)
    hidden = _limit("wave_generator_compliance", "Kw", 10.0, 5.0, 2.0, grows=-1.0)
    said = cannot_tell(_result([seen], limits=[hidden]))
    assert len(said) == 1 and "explains 5.0 %" in said[0]["why"]
