"""The report's table of detection limits (report._limits_section) reads as
sentences: units where a parameter has one, none for a ratio, and a limit
the search never reached said in words."""
from hdjoint.diagnosis.output.report import _limits_section


def test_limits_read_with_units_and_a_missing_limit_in_words():
    page = _limits_section([
        {"effect": "thermal_drift", "parameter": "Kt_warmup", "unit": "1", "reference": -0.03, "limit": -0.1,
         "times_reference": 3.4},
        {"effect": "wave_generator_compliance", "parameter": "Kw", "unit": "N.m/rad", "reference": 10.0,
         "limit": None, "times_reference": None, "reference_source": "the table's joint"}])
    assert "<td>-0.1 (3.4 times the reference)</td>" in page
    assert "<td>a torque-constant warm-up Kt_warmup of -0.03</td>" in page
    assert "a wave generator stiffness Kw of 10 N.m/rad (the table&#x27;s joint)" in page
    assert "none up to 1024 times that" in page
    assert "{" not in page and "None" not in page


def test_a_ripple_limit_names_its_order_in_the_table_and_in_words():
    from hdjoint.diagnosis.verdict.detection_limit import Limit
    limit = Limit("kinematic_error", "ke_l1_a", 1.45e-4, 3.45e-4, 2.38, 1.0, "1 arcmin (catalogue)",
                  at=("theta_l", 2.0))
    doc = limit.as_dict()
    assert doc["orders"] == [["theta_l", 2.0]]
    # The slot it was planted in (ke_l1_a) means nothing to a person: its role is said instead.
    assert limit.sentence().startswith("at theta_l order 2, it shows only from a cosine amplitude of 0.000345 rad "
                                       "(2.4 times the reference, 0.000145 rad, 1 arcmin (catalogue))")
    page = _limits_section([doc])
    assert "<td>kinematic_error at theta_l order 2</td>" in page and "<td>0.000345 rad (2.38 times" in page
    assert "a cosine amplitude of 0.000145 rad" in page
    assert "ke_l1_a" not in limit.sentence() + page


def test_a_limit_names_the_shape_it_was_planted_with():
    # A Stribeck rise's limit holds for a rise over its omega_s, not for every shape.
    from hdjoint.diagnosis.verdict.detection_limit import Limit, planted_shape, reference_set
    from hdjoint.diagnosis.effects import EFFECTS
    from hdjoint.io.parameters import defaults
    rise = EFFECTS["stribeck_friction"]
    shape = planted_shape(rise, reference_set(rise, defaults()))
    assert shape == (("omega_s", defaults()["omega_s"]),)
    limit = Limit("stribeck_friction", "Fs", 0.01, 0.002, 0.2, 1.0, "", shape=shape)
    assert limit.as_dict()["with"] == {"omega_s": 20.0}
    assert limit.sentence().startswith("with Stribeck speed omega_s = 20 rad/s, it shows only from a Stribeck "
                                       "friction Fs of 0.002 N.m")
    assert "<td>stribeck_friction with Stribeck speed omega_s = 20 rad/s</td>" in _limits_section([limit.as_dict()])
    # Terms switched off at the reference are no part of its shape (thermal drift's Fc_drift).
    thermal = planted_shape(EFFECTS["thermal_drift"], reference_set(EFFECTS["thermal_drift"], defaults()))
    assert thermal == (("Kt_warmup_tc", 10.0),)


def test_the_hysteresis_gets_no_limit():
    # Its test misses loops of other laws far past the size a planting of its own law shows.
    from hdjoint.diagnosis.effects import EFFECTS
    assert EFFECTS["hysteresis"].size is None
