"""Closure on a second recording (issue 10, item 5): the corrected parameter
set of a first diagnosis, used as the nominal set for another recording of
the same joint with another excitation, comes out `consistent` there.

On the independent truth (hdjoint_truth) the link's friction switches over
0.01 rad/s of link speed and the motor's over 0.1-2 rad/s. While the model
tied the link friction's smoothing to the motor's (omega_fc/N), the first
recording's corrected set failed on every second recording (0 of 3 seeds,
7e1c2e9): on this joint the second diagnosis resized Coulomb friction, on
seed 0 it left 32 % of the link channel's held-out residual as structure
against motor speed.

A time delay (here a first-order lag of the current sensor, 2.4 ms) named
on the paper excitation closes on a multisine only since the transmission
estimate stopped lagging by the fitted delay (on 7e1c2e9 the lag went
into Kf, Cf and eq. (7): `kinematic_error` resized at bl1 = -2.6e-4 where
the truth has 5.3e-5, and the second recording was `unexplained`)."""
import pytest

from hdjoint.io import parameters
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint_truth.cases import EFFECT_CASES, draw, record

pytestmark = pytest.mark.slow


def _case(name: str, seed: int):
    return draw(next(c for c in EFFECT_CASES if c.name == name), seed)


def test_time_delay_named_on_the_paper_excitation_closes_on_a_multisine():
    joint = _case("time delay", 0)
    assert [s.excitation for s in joint.setups] == ["paper", "multisine"]
    _, first = diagnose(record(joint, 0), joint.nominal)
    assert [f["effect"] for f in first["findings"]] == ["time_delay"], first["findings"]
    assert abs(first["params"]["bl1"] - joint.truth["bl1"]) < 2e-5  # eq. (7) no longer takes the lag
    _, second = diagnose(record(joint, 1), parameters.check(first["params"]))
    assert second["verdict"] == "consistent", (second["findings"], second["unexplained"])


def test_link_friction_named_on_a_sweep_closes_on_constant_speeds():
    joint = _case("link friction", 2)  # LuGre motor friction; a sweep, then constant speeds
    assert [s.excitation for s in joint.setups] == ["sweep", "constant_speeds"]
    _, first = diagnose(record(joint, 0), joint.nominal)
    assert [f["effect"] for f in first["findings"]] == ["link_friction"], first["findings"]
    corrected = first["params"]
    assert corrected["Fl"] == pytest.approx(joint.truth["Fl"], rel=0.1)
    # The link friction's own smoothing, fitted with it (the truth's: 0.01 rad/s).
    assert 0.005 < corrected["omega_fl"] < 0.02, corrected["omega_fl"]
    _, second = diagnose(record(joint, 1), parameters.check(corrected))
    assert second["verdict"] == "consistent", (second["findings"], second["unexplained"])


def test_cogging_named_on_a_sweep_closes_on_constant_speeds():
    """The order search finds the truth's cogging at motor order 6 on the sweep
    (held-out gain 68 %), and its fit must start from zero amplitude: with
    a unit of 1e-12 N.m the fit stayed there (gain 0). On the constant
    speeds the torsion's ripple is damped by Df at 30-100 Hz: unless sensor,
    compliance torque and damping rate pass one filter, the kinematic
    error's order 6 takes what the filter lost (p 4e-5, on a joint without one)."""
    joint = _case("cogging", 2)
    assert [s.excitation for s in joint.setups] == ["sweep", "constant_speeds"]
    _, first = diagnose(record(joint, 0), joint.nominal)
    assert [f["effect"] for f in first["findings"]] == ["cogging"], first["findings"]
    corrected = first["params"]
    assert corrected["cog_order"] == 6.0
    _, second = diagnose(record(joint, 1), parameters.check(corrected))
    assert second["verdict"] == "consistent", (second["findings"], second["unexplained"])


def test_a_joint_with_two_effects_closes_on_a_second_recording():
    """Several effects at once (issue 38): cogging and a current-sensor lag
    on one joint. Its corrected set, from a multisine, comes out `consistent`
    on a sweep of the same joint; nothing the joint lacks is named in their place."""
    joint = _case("two: cogging + time delay", 1)
    assert [s.excitation for s in joint.setups] == ["multisine", "sweep"]
    _, first = diagnose(record(joint, 0), joint.nominal)
    named = {f["effect"] for f in first["findings"]}
    assert "cogging" in named and named <= {"cogging", "time_delay"}, first["findings"]
    _, second = diagnose(record(joint, 1), parameters.check(first["params"]))
    assert second["verdict"] == "consistent", (second["findings"], second["unexplained"])
