"""Issue 12's FMU findings, one test each: bounded steps, a communication-point
tolerance that does not grow with the step, validated FMU states (each FMU its
own magic number and version), the FMI 2.0 state table in the error state,
and true initial dependencies in the modelDescription."""
from __future__ import annotations

import ctypes
import struct
import subprocess
import sys
import textwrap
import xml.etree.ElementTree as ET
import zipfile
import zlib

import numpy as np
import pytest
from fmpy.fmi1 import FMICallException

from hdjoint.fmu.shipped import fmu_path

from conftest import ALL_FMUS, CONTROLLER, ESTIMATOR, FMU_IO, JOINT

HEADER = 8  # serialised state: magic, version, state, time, start, stop, stop-defined, count
STATE, TIME, START = 2, 3, 4
INSTANTIATED, STEP_COMPLETE = 1.0, 4.0  # the glue's state bits
# ... then the model's fields, then the seal: zlib's CRC-32 of every byte before it.


def last_error(s) -> str:
    errors = s.errors()
    assert errors, f"no error was logged; messages: {s.messages}"
    return errors[-1]


def doubles(blob: bytes) -> list[float]:
    return list(struct.unpack(f"{len(blob) // 8}d", blob))


def pack(values) -> bytes:
    """VALUES (header and model fields, the seal left off) serialised and sealed, as the FMU does:
    what an edit that also forged the seal would give, so the fields' own checks are reached."""
    body = struct.pack(f"{len(values)}d", *values)
    return body + struct.pack("d", float(zlib.crc32(body)))


def unsealed(blob: bytes) -> list[float]:
    """The header and model fields of a serialised state, after checking its seal is zlib's CRC-32."""
    assert struct.unpack("d", blob[-8:])[0] == float(zlib.crc32(blob[:-8]))
    return doubles(blob[:-8])


def serialized(s) -> bytes:
    st = s.slave.getFMUstate()
    blob = s.slave.serializeFMUstate(st)
    s.slave.freeFMUstate(st)
    return bytes(blob)


# ---------------------------------------------------------------- bounded steps

# Run in a child with a timeout: before the bound, these steps never returned.
_HUGE_STEPS = textwrap.dedent("""
    import sys
    from hdjoint.fmu.runner import FmuError, FmuInstance
    from hdjoint.fmu.shipped import fmu_path
    name, params, h = sys.argv[1], eval(sys.argv[2]), float(sys.argv[3])
    with FmuInstance(fmu_path(name), "huge") as inst:
        inst.start(0.0, None, params, {})
        try:
            inst.call("fmi2DoStep", inst.slave.doStep, 0.0, h)
        except FmuError as e:
            print("REFUSED", e)
        else:
            print("ACCEPTED", inst.get([inst.description.modelVariables[-1].name]))
""")


@pytest.mark.parametrize("name, params, h", [
    (ESTIMATOR, {}, 1e300), (ESTIMATOR, {}, 1e5),
    (CONTROLLER, {}, 1e300), (CONTROLLER, {}, 1e5),
    (JOINT, {}, 1e6),                      # 1e10 substeps of the default max_step
    (JOINT, {"max_step": 1e-7}, 300.0),    # 3e9 substeps: overflowed int into one step
])
def test_a_step_beyond_the_bound_is_refused_at_once(name, params, h):
    done = subprocess.run([sys.executable, "-c", _HUGE_STEPS, name, repr(params), repr(h)],
                          capture_output=True, text=True, timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("REFUSED"), done.stdout
    assert "at most" in done.stdout and "split the step" in done.stdout, done.stdout


def test_the_joint_still_takes_a_long_step_within_the_bound(make_slave):
    s = make_slave(JOINT)
    s.start(params={"max_step": 1e-2}, inputs={"i_m": 0.0})
    s.slave.doStep(0.0, 100.0)  # 1e4 substeps: allowed
    assert np.all(np.isfinite(s.get(FMU_IO[JOINT][1])))


def test_the_communication_point_tolerance_does_not_grow_with_the_step(make_slave):
    s = make_slave(CONTROLLER)
    s.start(params={"Ts": 1.0})
    with pytest.raises(FMICallException):
        s.slave.doStep(0.05, 1e5)  # 0.05 s off: accepted before, as the tolerance was 1e-6*h
    assert "expected communication point 0" in last_error(s)


# ---------------------------------------------------------------- the error state


@pytest.mark.parametrize("name", ALL_FMUS)
def test_terminate_and_status_calls_are_refused_in_the_error_state(name, make_slave):
    s = make_slave(name)
    s.start()
    with pytest.raises(FMICallException):
        s.slave.doStep(1.0, 1e-3)  # not the expected communication point: error state
    value = ctypes.c_double()  # large enough for any of the four status types
    calls = {"fmi2Terminate": [ctypes.c_void_p]}
    for kind in ("", "Real", "Integer", "Boolean", "String"):
        calls[f"fmi2Get{kind}Status"] = [ctypes.c_void_p, ctypes.c_int, ctypes.c_void_p]
    for function, argtypes in calls.items():
        f = s.slave.dll[function]
        f.argtypes, f.restype = argtypes, ctypes.c_int
        args = [s.slave.component] + ([] if len(argtypes) == 1 else [2, ctypes.addressof(value)])
        assert f(*args) == 3, function  # fmi2Error
        assert function in last_error(s) and "state 'error'" in last_error(s), last_error(s)


# ---------------------------------------------------------------- validated states


@pytest.fixture
def started(make_slave):
    def make(name):
        s = make_slave(name)
        s.start()
        s.slave.doStep(0.0, 1e-3)
        return s
    return make


def refused_at_deserialize(s, blob) -> str:
    with pytest.raises(FMICallException):
        s.slave.deSerializeFMUstate(blob)
    return last_error(s)


def parameter_index(s, name) -> int:
    return HEADER + s.variables[name].valueReference  # every parameter, in table order, after the header


@pytest.mark.parametrize("name, parameter, value, why", [
    (ESTIMATOR, "Ts", 0.0, "outside"), (ESTIMATOR, "N", 0.0, "outside"), (ESTIMATOR, "Kf", float("nan"), "not finite"),
    (JOINT, "max_step", 0.0, "outside"), (CONTROLLER, "Ts", 0.0, "outside"),
])
def test_a_state_with_a_parameter_out_of_range_is_refused(name, parameter, value, why, started):
    s = started(name)
    v = unsealed(serialized(s))
    v[parameter_index(s, parameter)] = value
    message = refused_at_deserialize(s, pack(v))
    assert parameter in message and why in message, message


@pytest.mark.parametrize("name", ALL_FMUS)
def test_a_state_with_a_non_finite_model_field_is_refused(name, started):
    s = started(name)
    good = unsealed(serialized(s))
    for k in range(HEADER, len(good)):
        v = list(good)
        v[k] = float("nan")
        with pytest.raises(FMICallException):
            s.slave.deSerializeFMUstate(pack(v))
        # Named when the field is one of the FMU's; a sub-block's own layout check may refuse it first.
        assert "not finite" in last_error(s) or "does not fit" in last_error(s), (k, last_error(s))


@pytest.mark.parametrize("name", ALL_FMUS)
def test_step_complete_on_a_never_initialised_model_is_refused(name, make_slave):
    s = make_slave(name)  # instantiated only
    v = unsealed(serialized(s))
    v[STATE] = STEP_COMPLETE
    message = refused_at_deserialize(s, pack(v))
    assert "never initialised" in message, message


@pytest.mark.parametrize("name", ALL_FMUS)
def test_a_state_machine_value_that_is_no_state_is_refused(name, started):
    s = started(name)
    v = unsealed(serialized(s))
    v[STATE] = 3.0
    assert "state-machine value 3" in refused_at_deserialize(s, pack(v))


@pytest.mark.parametrize("name", ALL_FMUS)
def test_a_time_before_the_start_or_not_finite_is_refused(name, started):
    s = started(name)
    good = unsealed(serialized(s))
    for t in (-1.0, float("inf")):
        v = list(good)
        v[TIME] = t
        assert "not a finite time at or after the start" in refused_at_deserialize(s, pack(v))


@pytest.mark.parametrize("name", (ESTIMATOR, CONTROLLER))  # sampled models: the joint does not count samples
def test_a_far_future_time_makes_the_next_step_refused_not_hang(name, started):
    s = started(name)
    v = unsealed(serialized(s))
    v[TIME] = 1e300
    st = s.slave.deSerializeFMUstate(pack(v))
    s.slave.setFMUstate(st)
    s.slave.freeFMUstate(st)
    with pytest.raises(FMICallException):
        s.slave.doStep(1e300, 1e-3)
    assert "at most" in last_error(s)


@pytest.mark.parametrize("name", ALL_FMUS)
def test_another_version_of_this_fmus_state_is_refused(name, started):
    s = started(name)
    v = unsealed(serialized(s))
    v[1] += 1.0
    assert "state version" in refused_at_deserialize(s, pack(v))


@pytest.mark.parametrize("source, target", [(a, b) for a in ALL_FMUS for b in ALL_FMUS if a != b])
def test_a_state_of_another_hdjoint_fmu_is_refused_at_deserialize(source, target, started, make_slave):
    blob = serialized(started(source))
    t = make_slave(target)
    t.start()
    assert "not a state of this FMU" in refused_at_deserialize(t, blob)


@pytest.mark.parametrize("name", ALL_FMUS)
def test_every_edit_of_a_serialised_state_breaks_its_seal(name, started):
    # The fuzzer's finding: a state-machine field edited to another valid
    # state was accepted. Every value, the seal included, is tried.
    s = started(name)
    blob = serialized(s)
    for k in range(len(blob) // 8):
        edited = bytearray(blob)
        edited[8 * k] ^= 0x01  # the lowest mantissa bit: still a valid, finite number
        message = refused_at_deserialize(s, bytes(edited))
        assert "CRC-32 seal does not match" in message, (k, message)
    s.slave.freeFMUstate(s.slave.deSerializeFMUstate(blob))  # the untouched state still loads


@pytest.mark.parametrize("name", ALL_FMUS)
def test_a_resealed_state_before_initialisation_must_have_no_model_and_no_time_run(name, make_slave, started):
    # Behind the seal: a forged state whose state machine says "instantiated"
    # (legal before initialisation only) carrying an initialised model or a
    # time past its start is refused.
    v = unsealed(serialized(started(name)))
    v[STATE] = INSTANTIATED
    s = make_slave(name)
    message = refused_at_deserialize(s, pack(v))
    assert "comes before initialisation, but the model in it was initialised" in message, message
    s.slave.reset()  # out of the error state the refusal left: instantiated again
    fresh = unsealed(serialized(s))
    fresh[TIME] = fresh[START] + 1.0
    message = refused_at_deserialize(s, pack(fresh))
    assert "comes before any step" in message, message


# ---------------------------------------------------------------- initial dependencies


def initial_dependencies(name) -> dict[str, list[str]]:
    """{output: the inputs its InitialUnknown lists}, read from the raw XML (an absent
    attribute would mean 'every input', which fmpy does not tell apart)."""
    with zipfile.ZipFile(fmu_path(name)) as z:
        root = ET.fromstring(z.read("modelDescription.xml"))
    variables = root.find("ModelVariables").findall("ScalarVariable")
    deps = {}
    for u in root.find("ModelStructure").find("InitialUnknowns").findall("Unknown"):
        assert "dependencies" in u.attrib, u.attrib
        unknown = variables[int(u.attrib["index"]) - 1]
        if unknown.get("causality") != "output":  # Model Exchange's states and derivatives (the joint)
            continue
        indices = [int(k) for k in u.attrib["dependencies"].split()]
        deps[unknown.get("name")] = [variables[k - 1].get("name") for k in indices]
    return deps


@pytest.mark.parametrize("name", ALL_FMUS)
def test_initial_dependencies_are_declared_and_true(name, make_slave):
    inputs, outputs = FMU_IO[name]
    deps = initial_dependencies(name)
    assert list(deps) == list(outputs)
    assert all(set(d) <= set(inputs) for d in deps.values())
    base = {"i_m": 0.5, "theta_m": 10.0, "theta_l": 0.1, "tau_ext": 0.3, "tau_fb": 0.2}
    start = {k: base[k] for k in inputs}

    def initial_outputs(values):
        s = make_slave(name)
        s.start(inputs=values)
        return dict(zip(outputs, s.get(outputs)))

    reference = initial_outputs(start)
    for changed in inputs:
        moved = initial_outputs({**start, changed: start[changed] * 1.01 + 0.001})
        for out in outputs:
            if moved[out] != reference[out]:
                assert changed in deps[out], f"{out} moves with {changed} but does not declare it"


def test_no_initial_output_of_the_controller_or_the_joints_speeds_depends_on_inputs():
    # What breaks OMSimulator's initialisation loop across the three FMUs.
    assert all(d == [] for d in initial_dependencies(CONTROLLER).values())
    joint = initial_dependencies(JOINT)
    assert joint["omega_m"] == [] and joint["omega_link"] == [] and joint["theta_m"] == ["tau_ext"]
    assert initial_dependencies(ESTIMATOR)["omega_m"] == []
