"""The truth's effect size factor (hdjoint_truth.cases.draw(size=)): the
benchmark's joints at size 1, the effect alone scaled otherwise."""
import pytest

from hdjoint_truth.cases import EFFECT_CASES, draw


def _case(effect):
    return next(c for c in EFFECT_CASES if c.present == (effect,))


@pytest.mark.parametrize("effect", ["backlash", "stiffness_nonlinearity", "wave_generator_compliance",
                                    "kinematic_error", "hysteresis"])
def test_size_one_is_the_benchmarks_joint_and_other_draws_do_not_move(effect):
    base = draw(_case(effect), 1, 30.0)
    same, big = draw(_case(effect), 1, 30.0, size=1.0), draw(_case(effect), 1, 30.0, size=4.0)
    assert same.truth == base.truth and same.description == base.description
    # Everything but the effect is drawn the same: the nominal error, the form, the sensors, the excitations.
    moved = {k for k in base.truth if base.truth[k] != big.truth[k]}
    assert moved <= {"backlash", "Cf", "Kw", "bw_A", "dahl_H", "dahl_rate"}
    assert big.description == base.description and big.setups[0].excitation == base.setups[0].excitation


def test_size_scales_what_the_effect_does():
    assert draw(_case("backlash"), 0, size=4.0).truth["backlash"] == pytest.approx(
        4.0 * draw(_case("backlash"), 0).truth["backlash"])
    # A compliance grows as its stiffness falls; the shape parameter Cw stays.
    base, big = draw(_case("wave_generator_compliance"), 0), draw(_case("wave_generator_compliance"), 0, size=2.0)
    assert big.truth["Kw"] == pytest.approx(base.truth["Kw"] / 2.0) and big.truth["Cw"] == base.truth["Cw"]
    base, big = draw(_case("kinematic_error"), 3), draw(_case("kinematic_error"), 3, size=2.0)
    for (a, k, x, y), (a2, k2, x2, y2) in zip(base.form.extra_kinematic, big.form.extra_kinematic):
        assert (a, k) == (a2, k2) and x2 == pytest.approx(2 * x) and y2 == pytest.approx(2 * y)
