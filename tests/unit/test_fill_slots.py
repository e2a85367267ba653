"""Effect.fill_slots: orders into an effect's free slots, one allocator for
the channel search and the torsion view."""
from types import SimpleNamespace

from hdjoint.diagnosis.effects import EFFECTS


def _order(angle, k):
    return SimpleNamespace(angle=angle, order=k)


def test_orders_fill_free_slots_of_their_angle_in_turn_and_skip_a_full_angle():
    ke = EFFECTS["kinematic_error"]
    orders = [_order("theta_m", 3.0), _order("theta_l", 2.0), _order("theta_m", 5.0), _order("theta_m", 7.0)]
    trial, names, used = ke.fill_slots({}, orders)
    assert [(s, o.order) for s, o in used] == [("ke_m1", 3.0), ("ke_l1", 2.0), ("ke_m2", 5.0)]  # order 7: no slot left
    assert trial["ke_m1_order"] == 3.0 and trial["ke_m2_order"] == 5.0 and trial["ke_l1_order"] == 2.0
    assert names == ["ke_m1_a", "ke_m1_b", "ke_l1_a", "ke_l1_b", "ke_m2_a", "ke_m2_b"]


def test_a_slot_the_set_already_carries_is_not_reused_and_the_limit_holds():
    ke = EFFECTS["kinematic_error"]
    p = {"ke_m1_order": 2.0, "ke_m1_a": 6e-5, "ke_m1_b": 0.0}
    trial, names, used = ke.fill_slots(p, [_order("theta_m", 3.0), _order("theta_l", 4.0)], limit=1)
    assert [(s, o.order) for s, o in used] == [("ke_m2", 3.0)]
    assert trial["ke_m1_order"] == 2.0 and trial["ke_m1_a"] == 6e-5 and "ke_l1_order" not in trial
