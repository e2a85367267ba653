"""wg_load: the estimator's wave generator loaded by the transmitted torque
(as in the joint FMU) instead of the motor current (the paper's approximation)."""
import numpy as np

from hdjoint import _core
from hdjoint.io import parameters


def _exact_joint_run():
    """The joint open loop, encoders unquantised, no damping: the compliance
    chain is the only difference between plant and estimator."""
    p = dict(parameters.defaults(), motor_counts=0.0, link_counts=0.0, Df=0.0, Fc=0.03)
    t = np.arange(0.0, 2.0, 1e-3)
    i_m = 0.9 * np.sin(2 * np.pi * 0.7 * t) + 0.4  # moves the joint both ways against gravity
    sim = _core.simulate_joint(parameters.for_plant(p), t, i_m, np.zeros_like(t))
    return p, t, i_m, sim


def test_loaded_wave_generator_reproduces_the_joint_torque():
    p, t, i_m, sim = _exact_joint_run()
    # Row j's angles are the state at t_j, reached under the current of row j-1.
    i_applied = np.concatenate([[i_m[0]], i_m[:-1]])
    est = lambda w: _core.compliance(parameters.for_estimator(dict(p, wg_load=w)), i_applied,
                                     sim["theta_m"], sim["theta_l"])["tau_compliance"]
    paper, loaded = est(0.0) - sim["tau_joint"], est(1.0) - sim["tau_joint"]
    assert np.max(np.abs(loaded)) < 1e-8
    # The paper's tau_w = Kt*i_m carries friction and inertia into the wave generator's torsion.
    assert np.sqrt(np.mean(paper ** 2)) > 0.02


def test_wg_load_zero_is_the_paper_model_bit_for_bit():
    p, t, i_m, sim = _exact_joint_run()
    base = _core.compliance(parameters.for_estimator(p), i_m, sim["theta_m"], sim["theta_l"])
    explicit = _core.compliance(parameters.for_estimator(dict(p, wg_load=0.0)), i_m, sim["theta_m"], sim["theta_l"])
    assert np.array_equal(base["tau_compliance"], explicit["tau_compliance"])
    assert "wg_load" in parameters.defaults("estimator") and "wg_load" not in parameters.defaults("plant")
