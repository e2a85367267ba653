"""The FMI 3.0 Co-Simulation twins (NAME_fmi3.fmu): valid, the same variables
as the FMI 2.0 builds, the same outputs bit for bit, and the FMI 3.0 glue's
state machine, variable steps and sealed FMU state, all through fmpy."""
from __future__ import annotations

import struct
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

import fmpy
import numpy as np
import pytest
from fmpy import simulate_fmu
from fmpy.validation import validate_fmu

from hdjoint.fmu.shipped import FMU_NAMES, fmu_path

from conftest import ESTIMATOR, JOINT, Twin

DATA = Path(__file__).resolve().parents[1] / "data"


def _read(path):
    return np.genfromtxt(path, delimiter=",", names=True)


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmi3_twin_validates_with_no_problems(name):
    assert validate_fmu(str(fmu_path(name, 3))) == []


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmi3_twin_has_the_fmi2_variables_with_units(name):
    md2 = fmpy.read_model_description(str(fmu_path(name, 2)))
    md3 = fmpy.read_model_description(str(fmu_path(name, 3)))
    assert md3.fmiVersion == "3.0"
    assert md3.coSimulation.canHandleVariableCommunicationStepSize
    assert md3.coSimulation.canGetAndSetFMUstate and md3.coSimulation.canSerializeFMUstate
    v2 = {v.name: (v.valueReference, v.causality, v.unit, v.start) for v in md2.modelVariables}
    v3 = {v.name: (v.valueReference, v.causality, v.unit, v.start) for v in md3.modelVariables
          if v.causality != "independent"}
    assert v3 == v2
    assert all(v.type == "Float64" for v in md3.modelVariables)
    units = {u.name for u in md3.unitDefinitions}
    assert {v.unit for v in md3.modelVariables} <= units
    # The description names the FMI 3 spelling of the state capabilities (fmu4cpp's pitfall).
    root = ET.fromstring(zipfile.ZipFile(fmu_path(name, 3)).read("modelDescription.xml"))
    cs = root.find("CoSimulation")
    assert cs.get("canGetAndSetFMUState") == "true" and cs.get("canSerializeFMUState") == "true"
    assert cs.get("canGetAndSetFMUstate") is None


@pytest.mark.parametrize("name", [JOINT, ESTIMATOR])
def test_fmi3_outputs_equal_fmi2_outputs_bit_for_bit(name):
    inputs = _read(DATA / f"{name}_in.csv")
    ref = _read(DATA / f"{name}_ref.csv")
    outputs = [c for c in ref.dtype.names if c != "time"]
    results = [simulate_fmu(str(fmu_path(name, fmi)), stop_time=float(inputs["time"][-1]), output_interval=1e-3,
                            input=inputs, output=outputs) for fmi in (2, 3)]
    assert len(results[0]) == len(results[1]) == len(ref)
    for column in outputs:
        assert np.array_equal(results[0][column], results[1][column]), f"{name}.{column}: FMI 3 differs from FMI 2"
    assert np.ptp(results[1][outputs[0]]) > 0  # the run did something


# ---------------------------------------------------------------- the glue through fmpy's FMU3Slave


def test_fmi3_state_machine_is_enforced(tmp_path):
    t = Twin(JOINT, tmp_path)
    assert "must not be called in state 'Instantiated'" in t.refused(t.slave.doStep, 0.0, 1e-3)
    t.slave.reset()
    assert "no structural parameters" in t.refused(t.slave.fmi3EnterConfigurationMode, t.slave.component)
    t.slave.reset()
    t.start()
    assert "fixed after initialization" in t.refused(t.slave.setFloat64, [t.vr["Jl"]], [1.0])
    t.slave.reset()
    t.start()
    assert "hasEventMode is false" in t.refused(t.slave.enterStepMode)
    t.slave.reset()
    t.start(stop=0.01)
    t.slave.doStep(0.0, 0.005)
    assert "goes past stopTime" in t.refused(t.slave.doStep, 0.005, 0.01)
    assert "must not be called in state 'error'" in t.refused(t.slave.doStep, 0.005, 0.001)
    t.slave.reset()
    t.start()
    t.slave.terminate()
    assert "must not be called in state 'Terminated'" in t.refused(t.slave.doStep, 0.0, 1e-3)
    t.slave.freeInstance()


def test_fmi3_refuses_event_mode_it_does_not_have(tmp_path):
    with pytest.raises(Exception, match="Failed to instantiate"):
        Twin(ESTIMATOR, tmp_path, eventModeUsed=True)


def test_fmi3_steps_of_varying_size_match_fmi2(tmp_path):
    """canHandleVariableCommunicationStepSize: the same uneven grid gives the same outputs in both versions."""
    steps = [1e-3, 2.5e-3, 1e-4, 7e-3, 1e-3, 0.02, 3e-4, 0.01]
    twin = Twin(JOINT, tmp_path)
    twin.start()
    twin.slave.setFloat64([twin.vr["i_m"]], [0.4])
    from conftest import Slave  # the FMI 2.0 build, same grid
    unz2 = fmpy.extract(str(fmu_path(JOINT, 2)), str(tmp_path / "joint2"))
    s2 = Slave(unz2)
    s2.slave.setupExperiment(startTime=0.0)
    s2.slave.enterInitializationMode()
    s2.slave.exitInitializationMode()
    s2.slave.setReal([twin.vr["i_m"]], [0.4])
    names = [v.name for v in twin.md.modelVariables if v.causality == "output"]
    t = 0.0
    for h in steps:
        _, _, early, last = twin.slave.doStep(t, h)
        s2.slave.doStep(t, h)
        t += h
        assert not early and last == pytest.approx(t, abs=1e-15)
        assert np.array_equal(twin.outputs(), np.array(s2.slave.getReal([twin.vr[n] for n in names])))
    assert twin.slave.getFloat64([1000]) == [pytest.approx(t, abs=1e-15)]  # the independent variable time


def test_fmi3_state_round_trip_and_seal(tmp_path):
    t = Twin(ESTIMATOR, tmp_path)
    t.start()
    vr_in = [t.vr["i_m"], t.vr["theta_m"], t.vr["theta_l"]]
    time = 0.0
    for k in range(200):
        t.slave.setFloat64(vr_in, [0.3, 0.01 * k, 0.0001 * k])
        t.slave.doStep(time, 1e-3)
        time += 1e-3
    blob = t.slave.serializeFMUState(t.slave.getFMUState())
    after = []
    for k in range(50):
        t.slave.setFloat64(vr_in, [0.25, 0.01 * (200 + k), 0.0001 * (200 + k)])
        t.slave.doStep(time + k * 1e-3, 1e-3)
        after.append(t.outputs())
    state = t.slave.deserializeFMUState(blob)
    t.slave.setFMUState(state)
    for k in range(50):
        t.slave.setFloat64(vr_in, [0.25, 0.01 * (200 + k), 0.0001 * (200 + k)])
        t.slave.doStep(time + k * 1e-3, 1e-3)
        assert np.array_equal(t.outputs(), after[k])
    assert not np.array_equal(after[0], after[-1])
    # An edit of one field, even to a valid value, breaks the seal.
    edited = bytearray(blob)
    edited[8 * 3:8 * 4] = struct.pack("<d", struct.unpack("<d", blob[8 * 3:8 * 4])[0] + 1e-3)
    assert "seal does not match" in t.refused(t.slave.deserializeFMUState, bytes(edited))
    t.slave.freeInstance()


def test_fmi3_refuses_the_fmi2_builds_state(tmp_path):
    """The two versions' state machines differ: neither loads the other's serialised state."""
    from conftest import Slave
    s2 = Slave(fmpy.extract(str(fmu_path(JOINT, 2)), str(tmp_path / "joint2")))
    s2.slave.setupExperiment(startTime=0.0)
    s2.slave.enterInitializationMode()
    s2.slave.exitInitializationMode()
    blob = s2.slave.serializeFMUstate(s2.slave.getFMUstate())
    t = Twin(JOINT, tmp_path)
    assert "saved by the FMU's other FMI version" in t.refused(t.slave.deserializeFMUState, blob)
