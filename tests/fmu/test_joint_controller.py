"""JointController.fmu on its own: its law against a line-by-line Python
transcription of the documented equations, its reference and load, the JTF
switch, the current limit, and bad input (fmi2Error with a logged message,
like the other FMUs)."""
from __future__ import annotations

import math

import numpy as np
import pytest

from hdjoint.fmu.runner import FmuError, FmuInstance
from hdjoint.fmu.shipped import fmu_path

INPUTS = ("theta_m", "theta_l", "tau_fb")
OUTPUTS = ("i_m", "tau_ext", "theta_ref", "tau_d", "e_link")


def defaults() -> dict[str, float]:
    with FmuInstance(fmu_path("JointController"), "defaults") as c:
        return {name: float(v.start) for name, v in c.variables.items() if v.causality == "parameter"}


def run_fmu(params: dict[str, float], inputs: np.ndarray, h: float = 1e-3) -> np.ndarray:
    with FmuInstance(fmu_path("JointController"), "controller") as c:
        c.start(0.0, None, params)
        stepper = c.stepper(INPUTS, OUTPUTS)
        return np.array([list(stepper.step(k * h, h, u)) for k, u in enumerate(inputs)])


def run_python(p: dict[str, float], inputs: np.ndarray) -> np.ndarray:
    """The law of joint_controller.h, written out again (Ts = h)."""
    Ts, NKt = p["Ts"], p["N"] * p["Kt"]
    alpha = 1 - math.exp(-p["speed_filter"] * Ts)
    omega = rate = integral = 0.0
    prev = None
    out = []
    for k, (theta_m, theta_l, tau_fb) in enumerate(inputs):
        t = k * Ts
        if prev is not None:
            omega += alpha * ((theta_m - prev[0]) / Ts - omega)
            rate += alpha * ((tau_fb - prev[1]) / Ts - rate)
        prev = (theta_m, tau_fb)
        w = 2 * math.pi * p["ref_frequency"]
        ref = p["ref_offset"] + p["ref_amplitude"] * (1 - math.cos(w * t))
        ref_speed = p["ref_amplitude"] * w * math.sin(w * t)
        tau_d = NKt * (p["kp"] * (p["N"] * ref - theta_m) + p["kd"] * (p["N"] * ref_speed - omega)) \
            + p["mgl"] * math.sin(ref)
        cmd = tau_d
        if p["jtf"] == 1:
            e = tau_d - tau_fb
            limit = NKt * p["i_max"]
            base = cmd + p["k_tau"] * e - p["d_tau"] * rate
            cand = min(max(integral + p["ki_tau"] * Ts * e, -limit), limit)
            if abs(base + cand) <= limit or abs(base + cand) < abs(base + integral):
                integral = cand
            cmd = base + integral

        def rise(x):
            if x < 0:
                return 0.0
            if p["dist_rise"] <= 0 or x >= p["dist_rise"]:
                return 1.0
            u = x / p["dist_rise"]
            return u * u * (3 - 2 * u)
        load = p["dist_step"] * rise(t - p["dist_on"])
        if p["dist_off"] > p["dist_on"]:
            load -= p["dist_step"] * rise(t - p["dist_off"])
        load += p["dist_sine"] * math.sin(2 * math.pi * p["dist_frequency"] * t)
        out.append([min(max(cmd / NKt, -p["i_max"]), p["i_max"]), load, ref, tau_d, ref - theta_l])
    return np.array(out)


def joint_like_inputs(n: int, h: float = 1e-3, seed: int = 3) -> np.ndarray:
    t = np.arange(n) * h
    rng = np.random.default_rng(seed)
    theta_l = 0.5 * (1 - np.cos(2 * np.pi * 0.25 * t)) + 0.003 * np.sin(2 * np.pi * 3 * t)
    theta_m = 100 * theta_l + 0.02 * np.sin(2 * np.pi * 11 * t) + rng.normal(0, 1e-3, n)
    tau_fb = 2.5 * np.sin(2 * np.pi * 0.25 * t) + rng.normal(0, 0.05, n)
    return np.column_stack([theta_m, theta_l, tau_fb])


@pytest.mark.parametrize("changes", [
    {},                                                   # defaults: JTF on, PI torque loop
    {"jtf": 0.0},                                         # position PD only
    {"k_tau": 2.0, "ki_tau": 0.0, "d_tau": 0.003},        # P torque loop with damping
    {"i_max": 0.5, "ki_tau": 300.0},                      # the limit and the anti-windup at work
    {"dist_sine": 0.7, "dist_frequency": 3.0, "dist_rise": 0.0, "dist_on": 0.5, "dist_off": 0.1},
])
def test_the_fmu_computes_the_documented_law(changes):
    p = defaults() | {"dist_on": 0.4, "dist_off": 1.1} | changes
    u = joint_like_inputs(1500)
    got, want = run_fmu(p, u), run_python(p, u)
    assert np.ptp(got[:, 0]) > 0.1
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)
    if changes.get("i_max"):
        assert np.abs(got[:, 0]).max() == pytest.approx(0.5)


def test_jtf_off_ignores_the_torque_input_and_on_uses_it():
    u = joint_like_inputs(500)
    v = u.copy()
    v[:, 2] += 1.0
    p = defaults()
    assert np.array_equal(run_fmu(p | {"jtf": 0.0}, u), run_fmu(p | {"jtf": 0.0}, v))
    assert not np.array_equal(run_fmu(p, u)[:, 0], run_fmu(p, v)[:, 0])


def test_reference_starts_at_rest_and_the_load_steps_on_and_off():
    p = defaults()
    out = run_fmu(p, np.zeros((8001, 3)))
    t = np.arange(8001) * 1e-3
    assert out[0, 2] == 0.0                                # theta_ref(0) = ref_offset, at rest
    load = out[:, 1]
    assert np.all(load[t < p["dist_on"]] == 0.0)
    assert np.all(load[(t >= p["dist_on"] + p["dist_rise"]) & (t < p["dist_off"])] == p["dist_step"])
    assert np.all(load[t >= p["dist_off"] + p["dist_rise"]] == 0.0)


@pytest.mark.parametrize("variable", INPUTS)
@pytest.mark.parametrize("value", [math.nan, math.inf])
def test_non_finite_input_is_an_error_with_a_message(variable, value):
    with FmuInstance(fmu_path("JointController"), "bad") as c:
        c.start()
        with pytest.raises(FmuError) as e:
            c.call("fmi2SetReal", c.slave.setReal, c.value_references([variable]), [value])
        assert variable in str(e.value) and "not finite" in str(e.value)


def test_jtf_must_be_0_or_1():
    with FmuInstance(fmu_path("JointController"), "bad") as c:
        with pytest.raises(FmuError, match="jtf = 0.5"):
            c.start(0.0, None, {"jtf": 0.5})


def test_a_parameter_out_of_range_is_refused_naming_it():
    with FmuInstance(fmu_path("JointController"), "bad") as c:
        with pytest.raises(FmuError, match="kp = -1"):
            c.start(0.0, None, {"kp": -1.0})


def test_state_save_and_restore_continues_bit_for_bit():
    u = joint_like_inputs(600)
    with FmuInstance(fmu_path("JointController"), "state") as c:
        c.start()
        s = c.stepper(INPUTS, OUTPUTS)
        for k in range(300):
            s.step(k * 1e-3, 1e-3, u[k])
        state = c.slave.getFMUstate()
        first = np.array([list(s.step(k * 1e-3, 1e-3, u[k])) for k in range(300, 600)])
        c.slave.setFMUstate(state)
        second = np.array([list(s.step(k * 1e-3, 1e-3, u[k])) for k in range(300, 600)])
        c.slave.freeFMUstate(state)
    assert np.array_equal(first, second)
