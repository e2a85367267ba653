"""Issue 56's FMI call rules (found by a call-sequence fuzzer on the FMI 3.0
twins), one test each, in both FMI versions where the rule is in both:
Model Exchange functions on a Co-Simulation instance, an instance name of
whitespace only, a communication step of size 0, an infinite stop time (a
state saved with it could not be restored) and an enormous step's message."""
from __future__ import annotations

import ctypes
import math

import pytest
from fmpy.fmi1 import FMICallException

from hdjoint.fmu.shipped import FMU_NAMES

from conftest import Slave, Twin

ERROR = 3


@pytest.fixture
def twins(tmp_path):
    made = []

    def make(name, **kw):
        t = Twin(name, tmp_path / str(len(made)), **kw)
        made.append(t)
        return t

    yield make
    for t in made:
        t.slave.freeInstance()


# ---------------------------------------------------------------- 15: Model Exchange functions


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("function", ["fmi3GetNumberOfContinuousStates", "fmi3GetNumberOfEventIndicators"])
def test_fmi3_model_exchange_counts_are_refused_on_a_co_simulation_instance(name, function, twins):
    t = twins(name)
    call = getattr(t.slave.dll, function)
    call.argtypes, call.restype = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_size_t)], ctypes.c_int
    n = ctypes.c_size_t(12345)
    assert call(t.slave.component, ctypes.byref(n)) == ERROR
    assert n.value == 12345
    assert "Model Exchange function" in t.messages[-1] and function in t.messages[-1], t.messages


# ---------------------------------------------------------------- 16: instance names


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("instance_name", [" \t ", "\n", " "])
def test_an_instance_name_of_whitespace_only_is_refused(name, instance_name, tmp_path, unzipped):
    with pytest.raises(Exception, match="instantiate"):
        Twin(name, tmp_path, instance_name=instance_name)
    s = Slave(unzipped[name], instance_name, instantiate=False)
    with pytest.raises(Exception, match="instantiate"):
        s.instantiate()
    assert any("non-whitespace" in m or "not whitespace" in m for _, m in s.messages), s.messages


@pytest.mark.parametrize("name", FMU_NAMES)
def test_an_instance_name_with_a_visible_character_is_accepted(name, twins, make_slave):
    twins(name, instance_name=" a ")
    make_slave(name, " a ")


# ---------------------------------------------------------------- 17: step size


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("h", [0.0, -0.0])
def test_a_step_of_size_zero_is_refused(name, h, twins, make_slave):
    t = twins(name)
    t.start()
    message = t.refused(t.slave.doStep, 0.0, h)
    assert "fmi3DoStep" in message and "must be > 0" in message, message
    s = make_slave(name)
    s.start()
    with pytest.raises(FMICallException):
        s.slave.doStep(0.0, h)
    assert "fmi2DoStep" in s.errors()[-1] and "must be > 0" in s.errors()[-1], s.messages


# ---------------------------------------------------------------- 18: the stop time


@pytest.mark.parametrize("name", FMU_NAMES)
@pytest.mark.parametrize("stop", [math.inf, -math.inf, math.nan])
def test_a_stop_time_that_is_not_finite_is_refused_where_it_is_given(name, stop, twins, make_slave):
    t = twins(name)
    message = t.refused(t.slave.enterInitializationMode, None, 0.0, stop)
    assert "fmi3EnterInitializationMode" in message and "stopTime" in message, message
    s = make_slave(name)
    with pytest.raises(FMICallException):
        s.slave.setupExperiment(None, 0.0, stop)
    assert "fmi2SetupExperiment" in s.errors()[-1] and "stopTime" in s.errors()[-1], s.messages


@pytest.mark.parametrize("name", FMU_NAMES)
def test_every_state_the_fmu_saves_can_be_restored(name, twins):
    """With the stop time finite (or undefined), a state saved and serialised after initialisation deserialises."""
    for stop in (None, 1.0):
        t = twins(name)
        t.slave.enterInitializationMode(startTime=0.0, stopTime=stop)
        t.slave.exitInitializationMode()
        t.slave.doStep(0.0, 1e-3)
        state = t.slave.getFMUState()
        blob = t.slave.serializeFMUState(state)
        restored = t.slave.deserializeFMUState(blob)
        t.slave.setFMUState(restored)
        t.slave.doStep(1e-3, 1e-3)
        t.slave.freeFMUState(state)
        t.slave.freeFMUState(restored)


# ---------------------------------------------------------------- 14: an enormous step


@pytest.mark.parametrize("name", ["JointTorqueEstimator", "JointController"])
def test_an_enormous_step_is_refused_naming_its_count_plainly(name, twins):
    t = twins(name)
    t.start()
    message = t.refused(t.slave.doStep, 0.0, 1e300)
    assert "would run 1e+303 samples" in message, message
    assert "-9223372036854775808" not in message
