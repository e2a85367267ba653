"""Bad inputs, bad parameters, illegal call sequences: fmi2Error with a message
that says what went wrong, never a crash, and a way back (reset, saved state)."""
from __future__ import annotations

import ctypes
import math
import re
import subprocess
import sys
import textwrap

import numpy as np
import pytest
import scipy.optimize
from fmpy.fmi1 import FMICallException

from hdjoint.io import parameters
from hdjoint.fmu.runner import FmuError, FmuInstance, run_estimator_fmu

from conftest import (ESTIMATOR, ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS, FMU_NAMES, JOINT, JOINT_INPUTS,
                      JOINT_OUTPUTS, Slave, joint_test_inputs)
from reference_model import compliance

TS = 1e-3
IO = {ESTIMATOR: (ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS), JOINT: (JOINT_INPUTS, JOINT_OUTPUTS)}


def good_inputs(name, recording, n):
    if name == ESTIMATOR:
        r = recording
        return np.column_stack([r.i_m, r.theta_m, r.theta_l])[:n]
    return joint_test_inputs(n)


def last_error(s: Slave) -> str:
    errors = s.errors()
    assert errors, f"no error was logged; messages: {s.messages}"
    return errors[-1]


# ---------------------------------------------------------------- non-finite inputs


@pytest.mark.parametrize("value, text", [(math.nan, "nan"), (math.inf, "inf"), (-math.inf, "-inf")])
@pytest.mark.parametrize("name, variable", [(ESTIMATOR, v) for v in ESTIMATOR_INPUTS]
                         + [(JOINT, v) for v in JOINT_INPUTS])
def test_non_finite_input_is_refused_naming_variable_and_value(name, variable, value, text, make_slave):
    s = make_slave(name)
    s.start()
    with pytest.raises(FMICallException):
        s.set({variable: value})
    message = last_error(s)
    assert variable in message and text in message.lower(), message
    assert "fmi2SetReal" in message
    # The error is reported when the value is set, not silently held for later.
    assert len(s.errors()) == 1


@pytest.mark.parametrize("name", FMU_NAMES)
def test_non_finite_input_is_refused_in_initialization_mode(name, make_slave):
    s = make_slave(name)
    s.slave.setupExperiment(None, 0.0, None)
    s.slave.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.set({"i_m": math.nan})
    assert "i_m" in last_error(s) and "nan" in last_error(s)


# ---------------------------------------------------------------- parameters


OUT_OF_RANGE = [
    (ESTIMATOR, "N", 0.0, "N = 0"),
    (ESTIMATOR, "N", -1.0, "N = -1"),
    (ESTIMATOR, "Kf", math.nan, "Kf = nan"),
    (ESTIMATOR, "Kf", math.inf, "Kf = inf"),
    (ESTIMATOR, "N", 10000.5, "N = 10000.5"),
    (ESTIMATOR, "Ts", 0.0, "Ts = 0"),
    (ESTIMATOR, "ukf_alpha", 0.0, "ukf_alpha = 0"),
    (JOINT, "N", 0.0, "N = 0"),
    (JOINT, "N", -1.0, "N = -1"),
    (JOINT, "Kf", math.nan, "Kf = nan"),
    (JOINT, "max_step", 0.0, "max_step = 0"),
    (JOINT, "Jl", -0.1, "Jl = -0.10000000000000001"),
]


@pytest.mark.parametrize("name, param, value, text", OUT_OF_RANGE,
                         ids=[f"{'est' if n == ESTIMATOR else 'joint'}-{p}={v}" for n, p, v, _ in OUT_OF_RANGE])
def test_parameter_out_of_range_is_refused_naming_it(name, param, value, text, make_slave):
    s = make_slave(name)
    s.slave.setupExperiment(None, 0.0, None)
    s.slave.enterInitializationMode()
    with pytest.raises(FMICallException):
        s.set({param: value})
    message = last_error(s)
    assert text in message, message
    info = parameters.table()[param]
    if math.isfinite(value):
        m = re.search(r"valid range \[([^,\]]+), ([^\]]+)\]", message)
        assert m and (float(m[1]), float(m[2])) == (info.min, info.max), message


@pytest.mark.parametrize("name", FMU_NAMES)
def test_parameter_at_its_bounds_is_accepted(name, make_slave):
    s = make_slave(name)
    s.slave.setupExperiment(None, 0.0, None)
    s.slave.enterInitializationMode()
    info = parameters.table()["N"]
    s.set({"N": info.max})
    s.set({"N": info.min})
    assert s.get(["N"])[0] == info.min
    assert not s.errors()


@pytest.mark.parametrize("name", FMU_NAMES)
def test_setting_a_parameter_after_initialization_is_refused(name, make_slave):
    s = make_slave(name)
    s.start()
    with pytest.raises(FMICallException):
        s.set({"Kf": 9000.0})
    message = last_error(s)
    assert "Kf" in message and "initialization" in message, message
    assert s.get(["Kf"])[0] == parameters.table()["Kf"].default


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("when", ["initialization mode", "step complete"])
def test_setting_an_output_is_refused(name, when, make_slave):
    s = make_slave(name)
    if when == "step complete":
        s.start()
    else:
        s.slave.setupExperiment(None, 0.0, None)
        s.slave.enterInitializationMode()
    output = IO[name][1][0]
    with pytest.raises(FMICallException):
        s.set({output: 1.0})
    message = last_error(s)
    assert output in message and "output" in message, message


@pytest.mark.parametrize("name", FMU_NAMES)
def test_unknown_value_reference_is_refused(name, make_slave):
    s = make_slave(name)
    s.start()
    with pytest.raises(FMICallException):
        s.slave.getReal([987654])
    assert "987654" in last_error(s)
    s.slave.reset()
    s.start()
    with pytest.raises(FMICallException):
        s.slave.setReal([987654], [1.0])
    assert "987654" in last_error(s)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_integer_boolean_string_variables_do_not_exist(name, make_slave):
    s = make_slave(name)
    s.start()
    assert s.slave.getInteger([]) == []  # nothing asked: fine
    with pytest.raises(FMICallException):
        s.slave.setInteger([0], [1])
    assert "Integer" in last_error(s)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_unknown_log_category_is_refused(name, make_slave):
    s = make_slave(name)
    s.slave.setDebugLogging(True, ["logStatusError", "logStatusWarning", "logAll"])
    assert not s.errors()
    with pytest.raises(FMICallException):
        s.slave.setDebugLogging(True, ["logBogus"])
    assert "logBogus" in last_error(s)


# ---------------------------------------------------------------- singular torsion


def _theta_m_at(p, target):
    """Motor angle (link at 0, no current) where Cf*Kf*dtheta_f equals target, from the oracle."""
    def f(theta_m):
        dtheta_f, _ = compliance(p, 0.0, theta_m, 0.0)
        return p["Cf"] * p["Kf"] * float(dtheta_f) - target
    return scipy.optimize.brentq(f, -2.0, 2.0, xtol=1e-15)


@pytest.mark.parametrize("sign", [1, -1])
def test_estimator_torsion_beyond_the_asymptote_fails_the_step(sign, make_slave, estimator_params):
    p = estimator_params
    inside = _theta_m_at(p, sign * (math.pi / 2) * (1 - 1e-6))
    beyond = _theta_m_at(p, sign * (math.pi / 2) * (1 + 1e-6))
    s = make_slave(ESTIMATOR)
    s.start()
    s.set({"theta_m": inside})
    s.slave.doStep(0.0, TS)
    tau = s.get(["tau_compliance"])[0]
    assert sign * tau > 1e4  # near the asymptote, finite and huge
    assert not s.errors()
    s.set({"theta_m": beyond})
    # A sample beyond is a glitch (no torque explains it): predicted over, with a warning ...
    s.slave.doStep(TS, TS)
    assert not s.errors()
    assert "singular torsion" in s.messages[-1][1] and "treated as missing" in s.messages[-1][1], s.messages
    # ... until it has lasted 0.1 s: then it is the model, and the step fails.
    with pytest.raises(FMICallException):
        s.slave.doStep(2 * TS, 0.2)
    message = last_error(s)
    assert "singular torsion" in message, message
    assert "theta_m" in message and "since sample 1" in message, message


def test_joint_leaving_the_model_domain_fails_the_step(make_slave):
    s = make_slave(JOINT)
    s.start()
    s.set({"i_m": 1e4})  # 450 N.m on the motor shaft: far beyond the flexspline
    with pytest.raises(FMICallException):
        for k in range(50):
            s.slave.doStep(k * TS, TS)
    message = last_error(s)
    assert "singular torsion" in message, message


# ---------------------------------------------------------------- call sequences


def _init_mode(s):
    s.slave.setupExperiment(None, 0.0, None)
    s.slave.enterInitializationMode()


def _terminated(s):
    s.start()
    s.slave.doStep(0.0, TS)
    s.slave.terminate()


SEQUENCES = [
    ("doStep before setupExperiment", lambda s: None, lambda s: s.slave.doStep(0.0, TS),
     "fmi2DoStep", "instantiated"),
    ("doStep in initialization mode", _init_mode, lambda s: s.slave.doStep(0.0, TS),
     "fmi2DoStep", "initialization mode"),
    ("setupExperiment after initialization", lambda s: s.start(), lambda s: s.slave.setupExperiment(None, 0.0, None),
     "fmi2SetupExperiment", "step complete"),
    ("exitInitializationMode twice", lambda s: s.start(), lambda s: s.slave.exitInitializationMode(),
     "fmi2ExitInitializationMode", "step complete"),
    ("enterInitializationMode twice", _init_mode, lambda s: s.slave.enterInitializationMode(),
     "fmi2EnterInitializationMode", "initialization mode"),
    ("exitInitializationMode without enter", lambda s: s.slave.setupExperiment(None, 0.0, None),
     lambda s: s.slave.exitInitializationMode(), "fmi2ExitInitializationMode", "instantiated"),
    ("getReal before initialization", lambda s: None, lambda s: s.slave.getReal([0]),
     "fmi2GetReal", "instantiated"),
    ("doStep after terminate", _terminated, lambda s: s.slave.doStep(TS, TS), "fmi2DoStep", "terminated"),
    ("setReal after terminate", _terminated, lambda s: s.set({"i_m": 1.0}), "fmi2SetReal", "terminated"),
]


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("what, prepare, call, function, state", SEQUENCES, ids=[x[0] for x in SEQUENCES])
def test_illegal_call_sequence_is_an_error_naming_function_and_state(name, what, prepare, call, function, state,
                                                                    make_slave, recording):
    s = make_slave(name)
    prepare(s)
    with pytest.raises(FMICallException):
        call(s)
    message = last_error(s)
    assert function in message and f"'{state}'" in message, message
    # Still alive and usable after a reset.
    s.slave.reset()
    ins, outs = IO[name]
    u = good_inputs(name, recording, 20)
    s.start(inputs=dict(zip(ins, u[0])))
    got = s.run(0.0, [TS] * 20, u, ins, outs)
    assert np.isfinite(got).all()


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("t, h, text", [
    (0.0, -1e-3, "not a forward step"),
    (0.0, math.nan, "not a forward step"),
    (0.5, 1e-3, "expected communication point 0"),
    (0.0, 2.0, "stopTime"),
], ids=["negative-step", "nan-step", "jump", "past-stop-time"])
def test_bad_do_step_arguments_are_refused(name, t, h, text, make_slave):
    s = make_slave(name)
    s.start(stop_time=1.0)
    with pytest.raises(FMICallException):
        s.slave.doStep(t, h)
    message = last_error(s)
    assert "fmi2DoStep" in message and text in message, message


def test_wrong_guid_is_refused_at_instantiation(unzipped):
    s = Slave(unzipped[ESTIMATOR], "wrong", guid="{00000000-0000-0000-0000-000000000000}", instantiate=False)
    with pytest.raises(Exception, match="[Ff]ailed to instantiate"):
        s.instantiate()
    assert not s.slave.component
    message = last_error(s)
    assert "GUID" in message and "{00000000-0000-0000-0000-000000000000}" in message, message
    # The GUID of the other FMU is wrong too.
    other = Slave(unzipped[ESTIMATOR], "other", guid=Slave(unzipped[JOINT], "j", instantiate=False).description.guid,
                  instantiate=False)
    with pytest.raises(Exception):
        other.instantiate()


def test_model_exchange_and_empty_name_are_refused(unzipped):
    """Model Exchange only where the model has continuous states: the joint, not the estimator."""
    s = Slave(unzipped[ESTIMATOR], "x", instantiate=False)
    instantiate = s.slave.fmi2Instantiate  # raw: returns the component or None
    guid = s.description.guid.encode()
    callbacks = ctypes.byref(s.callbacks())
    assert instantiate(b"x", 0, guid, b"file:///", callbacks, 0, 0) is None  # fmi2ModelExchange
    assert "Co-Simulation" in last_error(s)
    assert instantiate(b"", 1, guid, b"file:///", callbacks, 0, 0) is None
    assert "instanceName" in last_error(s)
    j = Slave(unzipped[JOINT], "j", instantiate=False)
    component = j.slave.fmi2Instantiate(b"j", 0, j.description.guid.encode(), b"file:///",
                                        ctypes.byref(j.callbacks()), 0, 0)
    assert component is not None
    j.slave.fmi2FreeInstance(component)


# ---------------------------------------------------------------- states that do not fit


def test_a_state_of_the_other_fmu_is_refused(make_slave, recording):
    est = make_slave(ESTIMATOR)
    est.start()
    est.slave.doStep(0.0, TS)
    st = est.slave.getFMUstate()
    blob = est.slave.serializeFMUstate(st)
    est.slave.freeFMUstate(st)
    joint = make_slave(JOINT)
    joint.start()
    with pytest.raises(FMICallException):  # each FMU has its own magic number: refused at once
        joint.slave.deSerializeFMUstate(blob)
    assert "not a state of this FMU" in last_error(joint)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_garbage_and_truncated_serialized_states_are_refused(name, make_slave):
    s = make_slave(name)
    s.start()
    st = s.slave.getFMUstate()
    blob = s.slave.serializeFMUstate(st)
    s.slave.freeFMUstate(st)
    with pytest.raises(FMICallException):
        s.slave.deSerializeFMUstate(b"\x01" * len(blob))
    assert "CRC-32 seal does not match" in last_error(s)
    with pytest.raises(FMICallException):
        s.slave.deSerializeFMUstate(blob[:-8])
    with pytest.raises(FMICallException):
        s.slave.deSerializeFMUstate(blob[:20])
    assert "truncated" in last_error(s)


# ---------------------------------------------------------------- recovery


@pytest.mark.parametrize("name", FMU_NAMES)
def test_reset_after_an_error_gives_a_fresh_instance(name, make_slave, recording):
    ins, outs = IO[name]
    n = 200
    u = good_inputs(name, recording, n)
    params = {"Kf": 9500.0}
    fresh = make_slave(name, "fresh")
    fresh.start(params=params, inputs=dict(zip(ins, u[0])))
    expected = fresh.run(0.0, [TS] * n, u, ins, outs)

    s = make_slave(name, "recovered")
    s.start(params=params, inputs=dict(zip(ins, u[0])))
    s.run(0.0, [TS] * 30, u[:30], ins, outs)
    with pytest.raises(FMICallException):
        s.set({ins[0]: math.nan})
    with pytest.raises(FMICallException):  # in the error state, stepping is refused
        s.slave.doStep(30 * TS, TS)
    assert "'error'" in last_error(s)
    s.slave.reset()
    s.start(params=params, inputs=dict(zip(ins, u[0])))
    got = s.run(0.0, [TS] * n, u, ins, outs)
    assert np.array_equal(got, expected)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_set_state_after_a_failed_step_continues_correctly(name, make_slave, recording):
    ins, outs = IO[name]
    n0, n1 = 100, 150
    u = good_inputs(name, recording, n0 + n1)
    ref = make_slave(name, "reference")
    ref.start(inputs=dict(zip(ins, u[0])))
    expected = ref.run(0.0, [TS] * (n0 + n1), u, ins, outs)[n0:]

    s = make_slave(name, "recovered")
    s.start(inputs=dict(zip(ins, u[0])))
    s.run(0.0, [TS] * n0, u[:n0], ins, outs)
    saved = s.slave.getFMUstate()
    s.run(n0 * TS, [TS] * 10, u[n0:n0 + 10], ins, outs)
    bad = list(u[n0 + 10])
    if name == ESTIMATOR:
        bad[1] += 0.5  # theta_m: a move the joint can make in a sample, to a torsion beyond the asymptote
    else:
        bad[0] = 1e4   # i_m: drives the flexspline beyond it
    with pytest.raises(FMICallException):  # the estimator: after 0.1 s of it (before, a glitch predicted over)
        s.run((n0 + 10) * TS, [TS] * 150, [bad] * 150, ins, outs)
    assert "singular torsion" in last_error(s)
    s.slave.setFMUstate(saved)
    got = s.run(n0 * TS, [TS] * n1, u[n0:], ins, outs)
    assert np.array_equal(got, expected)
    s.slave.freeFMUstate(saved)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_twenty_instances_in_one_process_are_independent(name, make_slave, recording):
    ins, outs = IO[name]
    n = 150
    u_a = good_inputs(name, recording, n)
    u_b = u_a.copy()
    u_b[:, 0] = -0.5 * u_a[:, 0] + 0.3  # another current profile
    solo = {}
    for key, u in (("a", u_a), ("b", u_b)):
        s = make_slave(name, f"solo-{key}")
        s.start(inputs=dict(zip(ins, u[0])))
        solo[key] = s.run(0.0, [TS] * n, u, ins, outs)
    assert not np.array_equal(solo["a"], solo["b"])

    # All from the same loaded binary, stepped round robin.
    many = [make_slave(name, f"instance-{k}") for k in range(20)]
    which = ["a" if k % 2 == 0 else "b" for k in range(20)]
    profiles = {"a": u_a, "b": u_b}
    for s, key in zip(many, which):
        s.start(inputs=dict(zip(ins, profiles[key][0])))
    results = [np.empty((n, len(outs))) for _ in many]
    vin = many[0].vr(ins)
    vout = many[0].vr(outs)
    for j in range(n):
        for k, (s, key) in enumerate(zip(many, which)):
            s.slave.setReal(vin, list(profiles[key][j]))
            s.slave.doStep(j * TS, TS)
            results[k][j] = s.slave.getReal(vout)
    for k, key in enumerate(which):
        assert np.array_equal(results[k], solo[key]), f"instance {k} ({key}) differs from its solo run"
    # Messages went to the right instance: an error in one is not logged by the others.
    with pytest.raises(FMICallException):
        many[3].set({ins[0]: math.nan})
    assert len(many[3].errors()) == 1 and all(not s.errors() for k, s in enumerate(many) if k != 3)
    assert many[3].messages[-1][1].startswith("fmi2SetReal")


# ---------------------------------------------------------------- through hdjoint's own runner


def test_fmu_runner_reports_the_fmus_message(recording, estimator_params):
    r = recording.slice(0, 200)
    theta_m = r.theta_m.copy()
    theta_m[20:] += 0.5  # an encoder offset reached within the joint's speed: a torsion beyond the asymptote
    with pytest.raises(FmuError, match="singular torsion") as e:
        run_estimator_fmu(r.time, r.i_m, theta_m, r.theta_l, estimator_params)
    # Gated as a glitch for 0.1 s (100 samples), then the model is wrong: the run stops.
    assert "t = 0.12" in str(e.value) and "since sample 20" in str(e.value), str(e.value)


def test_fmu_instance_captures_messages(estimator_fmu):
    with FmuInstance(estimator_fmu, "captured") as inst:
        inst.start(0.0)
        with pytest.raises(FmuError, match="theta_l = inf"):
            inst.call("fmi2SetReal", inst.slave.setReal, inst.value_references(["theta_l"]), [math.inf])
        assert inst.messages[-1][0] == "ERROR"


# ---------------------------------------------------------------- null arguments, in a separate process


NULL_CALLS = textwrap.dedent(r"""
    import ctypes, sys
    lib = ctypes.CDLL(sys.argv[1])
    c = ctypes.c_void_p
    i = ctypes.c_int
    lib.fmi2DoStep.argtypes = [c, ctypes.c_double, ctypes.c_double, i]
    lib.fmi2SetReal.argtypes = [c, c, ctypes.c_size_t, c]
    lib.fmi2GetReal.argtypes = [c, c, ctypes.c_size_t, c]
    lib.fmi2GetFMUstate.argtypes = [c, c]
    lib.fmi2SetFMUstate.argtypes = [c, c]
    lib.fmi2FreeFMUstate.argtypes = [c, c]
    lib.fmi2SerializedFMUstateSize.argtypes = [c, c, c]
    lib.fmi2DeSerializeFMUstate.argtypes = [c, c, ctypes.c_size_t, c]
    lib.fmi2Reset.argtypes = [c]
    lib.fmi2Terminate.argtypes = [c]
    lib.fmi2FreeInstance.argtypes = [c]
    lib.fmi2CancelStep.argtypes = [c]
    lib.fmi2Instantiate.restype = c
    lib.fmi2Instantiate.argtypes = [ctypes.c_char_p, i, ctypes.c_char_p, ctypes.c_char_p, c, i, i]
    statuses = []
    # A NULL component everywhere.
    statuses += [lib.fmi2DoStep(None, 0.0, 1e-3, 1), lib.fmi2SetReal(None, None, 1, None),
                 lib.fmi2GetReal(None, None, 1, None), lib.fmi2GetFMUstate(None, None),
                 lib.fmi2SetFMUstate(None, None), lib.fmi2Reset(None), lib.fmi2Terminate(None),
                 lib.fmi2CancelStep(None)]
    lib.fmi2FreeInstance(None)
    # NULL callbacks and a NULL GUID.
    assert lib.fmi2Instantiate(b"x", 1, None, b"", None, 0, 0) is None
    comp = lib.fmi2Instantiate(b"x", 1, sys.argv[2].encode(), b"", None, 0, 0)
    assert comp, "instantiate without callbacks failed"
    # NULL arrays and state pointers on a live instance (no logger: must not crash either).
    statuses += [lib.fmi2SetReal(comp, None, 2, None), lib.fmi2Reset(comp), lib.fmi2GetReal(comp, None, 2, None),
                 lib.fmi2Reset(comp), lib.fmi2GetFMUstate(comp, None), lib.fmi2Reset(comp),
                 lib.fmi2SetFMUstate(comp, None), lib.fmi2Reset(comp),
                 lib.fmi2SerializedFMUstateSize(comp, None, None), lib.fmi2Reset(comp),
                 lib.fmi2DeSerializeFMUstate(comp, None, 8, None)]
    lib.fmi2FreeFMUstate(comp, None)
    lib.fmi2FreeInstance(comp)
    print(statuses)
""")


@pytest.mark.parametrize("name", FMU_NAMES)
def test_null_arguments_do_not_crash_the_host(name, unzipped):
    so = unzipped[name] / "binaries" / "linux64" / f"{name}.so"
    guid = Slave(unzipped[name], "g", instantiate=False).description.guid
    run = subprocess.run([sys.executable, "-c", NULL_CALLS, str(so), guid], capture_output=True, text=True,
                         timeout=60)
    assert run.returncode == 0, run.stderr
    statuses = eval(run.stdout.strip())
    # Every call with a NULL component fails with fmi2Error (3); the resets in between succeed (0).
    assert statuses[:8] == [3] * 8
    assert statuses[8:] == [3, 0, 3, 0, 3, 0, 3, 0, 3, 0, 3]


def test_fmu_instance_messages_stay_with_their_instance(estimator_fmu, joint_fmu):
    """Two FmuInstances alive at once (a co-simulation): an error in the first is reported with its message."""
    first = FmuInstance(estimator_fmu, "first")
    second = FmuInstance(joint_fmu, "second")
    try:
        first.start(0.0)
        second.start(0.0)
        with pytest.raises(FmuError) as e:
            first.call("fmi2SetReal", first.slave.setReal, first.value_references(["theta_l"]), [math.inf])
        assert "theta_l = inf" in str(e.value)
        assert ("ERROR", "fmi2SetReal: theta_l = inf is not finite") in first.messages
        assert not second.messages
    finally:
        second.close()
        first.close()


SURVIVOR = textwrap.dedent(r"""
    import gc, math
    from hdjoint.fmu.runner import FmuError, FmuInstance
    from hdjoint.fmu.shipped import fmu_path
    first = FmuInstance(fmu_path("JointTorqueEstimator"), "first")
    first.start(0.0)
    second = FmuInstance(fmu_path("HarmonicDriveJoint"), "second")
    second.start(0.0)
    second.close()
    del second
    gc.collect()
    junk = [bytearray(64) for _ in range(200000)]  # reuse the freed memory
    try:
        first.call("fmi2SetReal", first.slave.setReal, first.value_references(["theta_l"]), [math.inf])
    except FmuError as e:
        print(e)
    first.close()
""")


def test_closing_one_fmu_instance_leaves_the_others_logging_safely():
    """Instance A alive, instance B created and closed, then A logs an error: no crash, A gets its message."""
    run = subprocess.run([sys.executable, "-c", SURVIVOR], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, f"host process died with exit code {run.returncode}: {run.stderr[-500:]}"
    assert "theta_l = inf" in run.stdout
