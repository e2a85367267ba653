"""diagnosis.unresolved_harmonics: eq. (7) coefficients whose harmonic the
recording's travel does not resolve (structure.resolves, the rule the order
search uses too) cannot be resized into a kinematic-error finding."""
from types import SimpleNamespace

import numpy as np

from hdjoint.io import parameters
from hdjoint.diagnosis.model.prepare import unresolved_harmonics
from hdjoint.diagnosis.model.structure import candidate_orders, resolves


def _rec(motor_travel, link_travel):
    s = np.linspace(0.0, 1.0, 200)
    return SimpleNamespace(theta_m=motor_travel * s, theta_l=link_travel * s)


def test_a_harmonic_needs_one_and_a_half_periods_of_travel():
    assert resolves(1.0, 3 * np.pi + 1e-9) and not resolves(1.0, 3 * np.pi - 1e-6)
    assert resolves(2.0, 1.5 * np.pi + 1e-9) and not resolves(2.0, 1.5 * np.pi - 1e-6)
    assert candidate_orders("theta_l", 2.4) == [k for k in map(float, range(4, 41))]  # 4 * 2.4 >= 3 pi > 3 * 2.4


def test_a_short_link_travel_leaves_the_link_harmonic_unresolved_and_names_the_travel():
    p = parameters.defaults()
    out = unresolved_harmonics(_rec(motor_travel=160.0, link_travel=1.6), p)
    assert set(out) == {"al1", "bl1"}
    assert "theta_l travels 1.6 rad" in out["al1"] and "order 1" in out["al1"]


def test_a_motor_that_barely_turns_leaves_the_wave_generator_harmonics_unresolved_in_turn():
    p = parameters.defaults()
    # omega_w = 2: order 2 needs 1.5 pi rad, order 4 needs 0.75 pi rad
    out = unresolved_harmonics(_rec(motor_travel=1.2 * np.pi, link_travel=12.0), p)
    assert set(out) == {"aw1", "bw1"}
    assert unresolved_harmonics(_rec(motor_travel=160.0, link_travel=12.0), p) == {}
