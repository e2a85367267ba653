"""A ripple at an angle order shows when calibration would move one of the
effect's own terms (eq. (7) for the kinematic error) from within its
tolerance to beyond it (detection_limit.resized); a term already beyond
closes that route, and the effect then gets no limit (detection_limit._moved).
Which effects get a limit at all: detection_limit.untold_effects."""
from types import SimpleNamespace

from hdjoint.diagnosis.fit.priors import Prior
from hdjoint.diagnosis.verdict.detection_limit import _moved, resized
from hdjoint.diagnosis.effects import EFFECTS

KINEMATIC = EFFECTS["kinematic_error"]
DIAG = SimpleNamespace(objective=SimpleNamespace(priors={"al1": Prior(1e-4, 1e-4), "Kf": Prior(1e4, 1e3)},
                                                calibrated_names=["al1", "Kf"]))


def test_a_move_across_the_tolerance_shows_the_ripple():
    assert resized(DIAG, KINEMATIC, {"al1": 1.5e-4}, {"al1": 3e-4})       # 0.5 -> 3.5 tolerances
    assert resized(DIAG, KINEMATIC, {"al1": 1.5e-4}, {"al1": -4e-4})      # either side
    assert not resized(DIAG, KINEMATIC, {"al1": 1.5e-4}, {"al1": 1e-4})   # 0.5 -> 1.5: within


def test_only_the_effects_own_terms_count_and_a_term_already_beyond_closes_the_route():
    # Kf belongs to the stiffness, not the kinematic error
    assert not resized(DIAG, KINEMATIC, {"al1": 1e-4, "Kf": 1e4}, {"Kf": 5e3})
    assert not resized(DIAG, KINEMATIC, {"al1": 6e-4}, {"al1": 1e-4})
    assert _moved(DIAG, KINEMATIC, {"al1": 6e-4}) and not _moved(DIAG, KINEMATIC, {"al1": 3e-4})


def test_which_effects_get_a_limit():
    from hdjoint.diagnosis.verdict.detection_limit import untold_effects
    effects = [EFFECTS[e] for e in ("kinematic_error", "backlash", "time_delay", "cogging", "hysteresis")]
    within = {"al1": 1e-4, "ke_l1_a": 0.0, "ke_l1_b": 0.0}

    def selection(p):
        return SimpleNamespace(params=p, last_round=[], last_candidates=effects)
    # cogging and hysteresis have no Size (effects.py says why); a finding's effects (`told`) get none
    assert [e.id for e in untold_effects(DIAG, selection(within), {"time_delay"})] == ["kinematic_error", "backlash"]
    # a ripple whose slot the set already uses, or whose eq. (7) term already moved, gets none
    assert [e.id for e in untold_effects(DIAG, selection(dict(within, ke_l1_a=1e-5)))] == ["backlash", "time_delay"]
    assert [e.id for e in untold_effects(DIAG, selection(dict(within, al1=6e-4)))] == ["backlash", "time_delay"]
