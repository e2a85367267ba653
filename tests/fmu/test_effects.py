"""Physics beyond the paper (parameter_table.def's last section): every effect
is off by default and then changes nothing; switched on it has its signature;
the FMUs carry the parameters with their ranges and save/restore/serialise
their state exactly with the effects on; the batch path's stateful
compliance model, Dahl regressor and simulation extras."""
from __future__ import annotations

import numpy as np
import pytest
from fmpy import read_model_description

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.fmu.runner import FmuError, FmuInstance
from hdjoint.fmu.shipped import fmu_path

TS = 1e-3

# name: (scope, default) -- the beyond-the-paper parameters.
NEW = {
    "ke_m1_order": ("shared", 1.0), "ke_m1_a": ("shared", 0.0), "ke_m1_b": ("shared", 0.0),
    "ke_m2_order": ("shared", 3.0), "ke_m2_a": ("shared", 0.0), "ke_m2_b": ("shared", 0.0),
    "ke_l1_order": ("shared", 2.0), "ke_l1_a": ("shared", 0.0), "ke_l1_b": ("shared", 0.0),
    "ke_l2_order": ("shared", 4.0), "ke_l2_a": ("shared", 0.0), "ke_l2_b": ("shared", 0.0),
    "hys_H": ("shared", 0.0), "hys_sigma": ("shared", 2e4), "backlash": ("shared", 0.0),
    "Fs": ("shared", 0.0), "omega_s": ("shared", 20.0), "Fc_drift": ("shared", 0.0),
    "cog_order": ("shared", 6.0), "cog_a": ("shared", 0.0), "cog_b": ("shared", 0.0),
    "i_delay": ("estimator", 0.0), "wg_load": ("estimator", 0.0), "Fl": ("plant", 0.0),
    "lugre_sigma0": ("plant", 0.0), "lugre_sigma1": ("plant", 0.0),
    "bw_A": ("plant", 0.0), "bw_beta": ("plant", 0.0), "bw_gamma": ("plant", 0.0),
    "thermal_gain": ("plant", 0.0), "thermal_tc": ("plant", 20.0), "omega_fl": ("plant", 0.01),
    "Kt_warmup": ("shared", 0.0), "Kt_warmup_tc": ("shared", 15.0),
}

# Every effect on, at sizes a real joint could have.
EFFECTS = {
    "ke_m1_a": 2e-5, "ke_m2_b": -1e-5, "ke_l1_a": 3e-5, "ke_l2_b": 1e-5,
    "hys_H": 0.3, "hys_sigma": 3e4, "backlash": 5e-5, "Fs": 0.01, "omega_s": 8.0, "Fc_drift": 0.004,
    "cog_a": 0.004, "cog_b": -0.002, "i_delay": 3e-3, "Fl": 0.5,
    "lugre_sigma0": 2e4, "lugre_sigma1": 0.02, "bw_A": 5e3, "bw_beta": 2e4, "bw_gamma": 1e4,
    "thermal_gain": 0.5, "thermal_tc": 0.5, "Kt_warmup": -0.05, "Kt_warmup_tc": 0.4,
}


def plant_params(extra=None):
    return parameters.for_plant({**parameters.defaults(), **(extra or {})})


def estimator_params(extra=None):
    return parameters.for_estimator({**parameters.defaults(), **(extra or {})})


def drive(n, dt=TS):
    t = np.arange(n) * dt
    i_m = 1.2 * np.sin(2 * np.pi * 0.8 * t) + 0.4 * np.sin(2 * np.pi * 7.0 * t) + 0.3 * (t > 0.2)
    tau_ext = 0.4 * np.sin(2 * np.pi * 0.3 * t)
    return t, i_m, tau_ext


def triangle(n, period, amplitude):
    k = np.arange(n) % period
    q = period // 4
    return amplitude * np.where(k <= q, k / q, np.where(k <= 3 * q, (2 * q - k) / q, (k - 4 * q) / q))


# ---------------------------------------------------------------- the table


def test_every_new_parameter_is_in_the_table_switched_off():
    table = parameters.table()
    for name, (scope, default) in NEW.items():
        assert name in table, name
        assert table[name].scope == scope, name
        assert table[name].default == default, name
        assert table[name].min <= default <= table[name].max, name
    # Value references of the paper's parameters did not move: the new ones come after.
    # (The joint-state filter's settings, jsf_*, std_nis_time and omega_fl came later still, and the
    # bounds of the estimator's gate on wild readings, i_peak and omega_m_max.)
    later = ("std_nis_time", "i_peak", "omega_m_max")
    paper = [n for n in table if n not in NEW and not n.startswith("jsf_") and n not in later]
    assert max(table[n].value_reference for n in paper) < min(table[n].value_reference for n in NEW)


@pytest.mark.parametrize("fmu,in_scope", [("JointTorqueEstimator", ("shared", "estimator")),
                                          ("HarmonicDriveJoint", ("shared", "plant"))])
def test_fmus_carry_the_new_parameters_with_ranges(fmu, in_scope):
    md = read_model_description(str(fmu_path(fmu)))
    variables = {v.name: v for v in md.modelVariables}
    table = parameters.table()
    for name, (scope, default) in NEW.items():
        if scope not in in_scope:
            assert name not in variables, f"{fmu} should not carry {name}"
            continue
        v = variables[name]
        assert v.causality == "parameter" and float(v.start) == default
        assert float(v.min) == table[name].min and float(v.max) == table[name].max
        assert v.unit == table[name].unit


# ---------------------------------------------------------------- off changes nothing


def test_switched_off_effects_change_no_bit():
    """Each switch off, with every companion parameter moved: the paper's model, bit for bit."""
    companions = {"ke_m1_order": 5.0, "ke_m2_order": 9.0, "ke_l1_order": 0.5, "ke_l2_order": 11.0,
                  "hys_sigma": 7e5, "omega_s": 2.0, "cog_order": 13.0, "lugre_sigma1": 0.4,
                  "bw_beta": 3.0, "bw_gamma": 4.0, "thermal_tc": 0.1, "i_delay": 0.4 * TS,
                  "Kt_warmup_tc": 0.2}
    t, i_m, tau_ext = drive(1500)
    ref = _core.simulate_joint(plant_params(), t, i_m, tau_ext)
    got = _core.simulate_joint(plant_params(companions), t, i_m, tau_ext)
    for key in ref:
        assert np.array_equal(ref[key], got[key]), key
    est_ref = _core.run_estimator(estimator_params(), t, i_m, ref["theta_m"], ref["theta_l"])
    est_got = _core.run_estimator(estimator_params(companions), t, i_m, ref["theta_m"], ref["theta_l"])
    for key in est_ref:
        assert np.array_equal(est_ref[key], est_got[key]), key
    assert not np.any(est_ref["hysteresis_torque"])
    assert not np.any(ref["z_hysteresis"]) and not np.any(ref["tau_cogging"]) and not np.any(ref["tau_link_friction"])
    assert np.all(ref["friction_scale"] == 1.0)


# ---------------------------------------------------------------- Dahl regressor


def test_dahl_loop_is_2H_high_and_rate_independent():
    H, sigma = 0.4, 2e4
    x = triangle(2000, 400, 20 * H / sigma)
    z = _core.dahl(x, H, sigma)
    assert z[0] == 0.0
    up, down = z[800], z[1000]  # x = 0 going up, x = 0 going down (second cycle)
    assert up - down == pytest.approx(2 * H, rel=1e-6)
    assert np.all(np.abs(z) <= H)
    # The same path four times more finely sampled: the same z where they meet.
    fine = _core.dahl(triangle(8000, 1600, 20 * H / sigma), H, sigma)
    np.testing.assert_allclose(fine[::4], z, atol=1e-12)
    assert not np.any(_core.dahl(x, 0.0, sigma))  # H = 0: off
    with pytest.raises(ValueError):
        _core.dahl(x, -1.0, sigma)
    with pytest.raises(ValueError):
        _core.dahl(x, H, 0.0)


# ---------------------------------------------------------------- stateful compliance model


def test_compliance_model_carries_the_hysteresis():
    p = estimator_params({"hys_H": 0.3, "hys_sigma": 3e4, "al1": 0.0, "bl1": 0.0, "aw1": 0.0, "bw1": 0.0,
                          "aw2": 0.0, "bw2": 0.0})
    torsion = triangle(1200, 400, 6e-4)
    theta_l = np.full_like(torsion, 0.2)
    theta_m = p["N"] * (theta_l + torsion)
    i_m = np.zeros_like(torsion)
    on = _core.compliance(p, i_m, theta_m, theta_l)
    off = _core.compliance({**p, "hys_H": 0.0}, i_m, theta_m, theta_l)
    z = _core.dahl(on["dtheta_f"], 0.3, 3e4)
    assert np.array_equal(on["hysteresis_torque"], z)
    assert np.array_equal(on["tau_compliance"], off["tau_compliance"] + z)
    assert np.array_equal(on["dtheta_f"], off["dtheta_f"])
    assert not np.any(off["hysteresis_torque"])


def test_compliance_model_with_delay_is_the_undelayed_one_shifted():
    n = 7
    t, i_m, tau_ext = drive(800)
    sim = _core.simulate_joint(plant_params(), t, i_m, tau_ext)
    p = estimator_params({"hys_H": 0.2})
    ref = _core.compliance(p, i_m, sim["theta_m"], sim["theta_l"])
    # The current sensor lags: row k shows the current of row k - n.
    lagged = np.concatenate([np.full(n, i_m[0]), i_m[:-n]])
    got = _core.compliance({**p, "i_delay": n * TS}, lagged, sim["theta_m"], sim["theta_l"])
    for key in ("tau_compliance", "dtheta_f", "hysteresis_torque"):
        assert np.array_equal(got[key][n:], ref[key][:-n]), key
    est_ref = _core.run_estimator(p, t, i_m, sim["theta_m"], sim["theta_l"])
    est = _core.run_estimator({**p, "i_delay": n * TS}, t, lagged, sim["theta_m"], sim["theta_l"])
    assert np.array_equal(est["tau_ukf"][n:], est_ref["tau_ukf"][:-n])


def test_backlash_reads_zero_torque_inside_the_band():
    p = estimator_params({"backlash": 4e-4, "al1": 0.0, "bl1": 0.0, "aw1": 0.0, "bw1": 0.0, "aw2": 0.0, "bw2": 0.0})
    torsion = np.linspace(-6e-4, 6e-4, 121)
    theta_l = np.zeros_like(torsion)
    out = _core.compliance(p, np.zeros_like(torsion), p["N"] * torsion, theta_l)
    inside = np.abs(torsion) <= 2e-4
    assert np.all(out["tau_compliance"][inside] == 0.0)
    assert np.all(np.abs(out["tau_compliance"][~inside]) > 0.0)


# ---------------------------------------------------------------- the joint's extras


def test_simulation_extras_show_friction_cogging_and_hysteresis():
    t, i_m, tau_ext = drive(2000)
    p = plant_params({"Fs": 0.02, "omega_s": 5.0, "cog_a": 0.003, "hys_H": 0.2, "thermal_gain": 0.6,
                      "thermal_tc": 0.4, "motor_counts": 0.0, "link_counts": 0.0})
    sim = _core.simulate_joint(p, t, i_m, tau_ext)
    w = sim["omega_m"]
    scale = 1 + 0.6 * (1 - np.exp(-t / 0.4))
    np.testing.assert_allclose(sim["friction_scale"], scale, rtol=1e-12)
    stribeck = (p["Fc"] + 0.02 * np.exp(-(w / 5.0) ** 2)) * np.tanh(w / p["omega_fc"])
    np.testing.assert_allclose(sim["tau_friction"], scale * stribeck + p["Bm"] * w, rtol=1e-10, atol=1e-15)
    np.testing.assert_allclose(sim["tau_cogging"], 0.003 * np.cos(p["cog_order"] * sim["theta_m"]), atol=1e-15)
    assert np.max(np.abs(sim["z_hysteresis"])) <= 0.2 * 1.01
    assert np.ptp(sim["z_hysteresis"]) > 0.2


# ---------------------------------------------------------------- the FMUs with the effects on


def _recording_with_effects(n=1200):
    t, i_m, tau_ext = drive(n)
    sim = _core.simulate_joint(plant_params(EFFECTS), t, i_m, tau_ext)
    return t, i_m, tau_ext, sim


@pytest.mark.parametrize("fmu", ["JointTorqueEstimator", "HarmonicDriveJoint"])
def test_fmu_state_restores_and_serialises_exactly_with_effects_on(fmu):
    t, i_m, tau_ext, sim = _recording_with_effects()
    if fmu == "JointTorqueEstimator":
        params, names = parameters.for_estimator(EFFECTS), ("i_m", "theta_m", "theta_l")
        rows = np.column_stack([i_m, sim["theta_m"], sim["theta_l"]])
        outs = ("tau_ukf", "tau_compliance", "omega_m", "dtheta_f", "tau_ukf_std")
    else:
        params, names = parameters.for_plant(EFFECTS), ("i_m", "tau_ext")
        rows = np.column_stack([i_m, tau_ext])
        outs = ("theta_m", "theta_l", "tau_joint", "omega_m", "omega_link")
    n0, n1 = 500, 600
    with FmuInstance(fmu_path(fmu), "a") as a, FmuInstance(fmu_path(fmu), "b") as b:
        a.start(0.0, None, params, dict(zip(names, rows[0])))
        run = a.stepper(names, outs)
        for k in range(n0):
            run.step(k * TS, TS, rows[k])
        state = a.slave.getFMUstate()
        blob = a.slave.serializeFMUstate(state)
        first = np.array([list(run.step(k * TS, TS, rows[k])) for k in range(n0, n0 + n1)])
        assert np.all(np.ptp(first, axis=0)[:3] > 0)
        # Back to the saved state in the same instance...
        a.slave.setFMUstate(state)
        again = np.array([list(run.step(k * TS, TS, rows[k])) for k in range(n0, n0 + n1)])
        assert np.array_equal(first, again)
        a.slave.freeFMUstate(state)
        # ...and, serialised, in another instance.
        b.start(0.0, None, params, dict(zip(names, rows[0])))
        restored = b.slave.deSerializeFMUstate(blob)
        b.slave.setFMUstate(restored)
        other = b.stepper(names, outs)
        elsewhere = np.array([list(other.step(k * TS, TS, rows[k])) for k in range(n0, n0 + n1)])
        assert np.array_equal(first, elsewhere)
        b.slave.freeFMUstate(restored)


def test_estimator_fmu_equals_the_batch_path_with_effects_on():
    from hdjoint.fmu.runner import run_estimator_fmu
    t, i_m, _, sim = _recording_with_effects(800)
    p = parameters.for_estimator(EFFECTS)
    fmu = run_estimator_fmu(t, i_m, sim["theta_m"], sim["theta_l"], p)
    batch = _core.run_estimator(estimator_params(EFFECTS), t, i_m, sim["theta_m"], sim["theta_l"])
    for key in fmu:
        assert np.array_equal(fmu[key], batch[key]), key
    paper = _core.run_estimator(estimator_params(), t, i_m, sim["theta_m"], sim["theta_l"])
    assert np.max(np.abs(paper["tau_compliance"] - batch["tau_compliance"])) > 0.05


def test_joint_fmu_equals_the_batch_path_with_effects_on():
    from fmpy import simulate_fmu
    t, i_m, tau_ext, sim = _recording_with_effects(600)
    inputs = np.array(list(zip(t, i_m, tau_ext)), dtype=[("time", float), ("i_m", float), ("tau_ext", float)])
    result = simulate_fmu(str(fmu_path("HarmonicDriveJoint")), stop_time=float(t[-1]), step_size=TS,
                          output_interval=TS, input=inputs, start_values=parameters.for_plant(EFFECTS),
                          output=["tau_joint", "omega_m"])
    np.testing.assert_allclose(result["tau_joint"], sim["tau_joint"], rtol=0, atol=1e-9)
    np.testing.assert_allclose(result["omega_m"], sim["omega_m"], rtol=0, atol=1e-9)


@pytest.mark.parametrize("fmu,name,value", [
    ("JointTorqueEstimator", "hys_H", -0.1), ("JointTorqueEstimator", "backlash", 0.02),
    ("JointTorqueEstimator", "Fc_drift", 0.5), ("JointTorqueEstimator", "i_delay", 0.2),
    ("JointTorqueEstimator", "ke_m1_a", 0.1), ("JointTorqueEstimator", "cog_order", -1.0),
    ("HarmonicDriveJoint", "Fl", -1.0), ("HarmonicDriveJoint", "lugre_sigma0", -5.0),
    ("HarmonicDriveJoint", "bw_beta", 2e6), ("HarmonicDriveJoint", "thermal_gain", -0.95),
    ("HarmonicDriveJoint", "Fs", float("nan")), ("JointTorqueEstimator", "Kt_warmup", -0.8),
    ("HarmonicDriveJoint", "Kt_warmup_tc", 0.0), ("HarmonicDriveJoint", "Kt_warmup", 0.01),
])
def test_fmu_refuses_new_parameters_out_of_range(fmu, name, value):
    with FmuInstance(fmu_path(fmu), "bad") as inst:
        with pytest.raises(FmuError, match=f"{name} = .*(valid range|not finite)"):
            inst.start(0.0, None, {name: value})


def test_estimator_fmu_refuses_a_delay_longer_than_128_samples():
    with FmuInstance(fmu_path("JointTorqueEstimator"), "bad") as inst:
        with pytest.raises(FmuError, match="at most 128 samples"):
            inst.start(0.0, None, {"i_delay": 0.05, "Ts": 1e-4})
