"""A ripple at an angle order shows when calibration would move one of the
effect's own terms (eq. (7) for the kinematic error) from within its
tolerance to beyond it (detection_limit.resized); a term already beyond
closes that route, and the effect then gets no limit (detection_limit._moved)."""
from types import SimpleNamespace

from hdjoint.calibration import Prior
from hdjoint.detection_limit import _moved, resized
from hdjoint.effects import EFFECTS

KINEMATIC = EFFECTS["kinematic_error"]
DIAG = SimpleNamespace(priors={"al1": Prior(1e-4, 1e-4), "Kf": Prior(1e4, 1e3)}, calibrated_names=["al1", "Kf"])


def test_a_move_across_the_tolerance_shows_the_ripple():
    assert resized(DIAG, KINEMATIC, {"al1": 1.5e-4}, {"al1": 3e-4})       # 0.5 -> 3.5 tolerances
    assert resized(DIAG, KINEMATIC, {"al1": 1.5e-4}, {"al1": -4e-4})      # either side
    assert not resized(DIAG, KINEMATIC, {"al1": 1.5e-4}, {"al1": 1e-4})   # 0.5 -> 1.5: within


def test_only_the_effects_own_terms_count_and_a_term_already_beyond_closes_the_route():
    # Kf belongs to the stiffness, not the kinematic error
    assert not resized(DIAG, KINEMATIC, {"al1": 1e-4, "Kf": 1e4}, {"Kf": 5e3})
    assert not resized(DIAG, KINEMATIC, {"al1": 6e-4}, {"al1": 1e-4})
    assert _moved(DIAG, KINEMATIC, {"al1": 6e-4}) and not _moved(DIAG, KINEMATIC, {"al1": 3e-4})
