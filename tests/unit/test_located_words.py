"""Where a located structure is largest is said in the feature's own terms:
the loading-vs-unloading scan codes loading samples as torque + 1e4 N.m, and
an unexplained entry read "largest at 1e+04 to 1e+04 N.m" (issue 38)."""
import numpy as np

from hdjoint.diagnosis.verdict.findings import LOADING_CODE, _direction_bin, _loading_bin
from hdjoint.diagnosis.model.structure import scan


def test_the_loading_scan_says_torque_and_direction_not_its_code():
    rng = np.random.default_rng(0)
    n = 4000
    torque = 5.0 * np.sin(np.linspace(0, 40 * np.pi, n))
    loading = np.gradient(torque) > 0
    residual = np.where(loading & (torque > 3.0), 1.0, 0.0) + 0.05 * rng.standard_normal(n)
    fold = np.repeat(np.arange(40), n // 40)
    train, test = fold % 2 == 0, fold % 2 == 1
    coded = {"torque, loading vs unloading": (torque + LOADING_CODE * loading, None, "N.m", _loading_bin)}
    peak = scan(residual, coded, fold, train, test)[0].peak_at
    assert peak.endswith("N.m while loading") and "e+04" not in peak
    low, high = (float(x) for x in peak.split(" N.m")[0].split(" to "))
    assert 0.0 < low < high <= 5.0


def test_a_bin_across_the_code_is_said_so():
    assert _loading_bin(-2.0, LOADING_CODE + 1.0) == "torques across loading and unloading"
    assert _loading_bin(-2.0, 1.0) == "-2 to 1 N.m while unloading"


def test_a_negative_torque_while_moving_forward_is_said_as_forward():
    # Coded as torque + 1e4, it lies below the code but far above any torque.
    assert _direction_bin(LOADING_CODE - 3.0, LOADING_CODE - 1.0) == "-3 to -1 N.m, moving forward"
    assert _direction_bin(-3.0, 2.0) == "-3 to 2 N.m, moving back"
