"""Shared fixtures for the FMU and CLI tests.

Everything here uses the INSTALLED hdjoint package (pip install .), never the
source tree under python/: the tests check what users get.
"""
from __future__ import annotations

import ctypes
import sys
from pathlib import Path

import numpy as np
import pytest

# reference_model.py (the numpy oracle) lives next to the tests.
TESTS_DIR = Path(__file__).resolve().parent
if str(TESTS_DIR) not in sys.path:
    sys.path.insert(0, str(TESTS_DIR))

import fmpy  # noqa: E402
from fmpy.fmi2 import (FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,  # noqa: E402
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)

import hdjoint  # noqa: E402
from hdjoint.io import parameters  # noqa: E402
from hdjoint.fmu.shipped import fmu_path  # noqa: E402
# Each FMU's inputs and outputs, from its C++ signal table (not retyped here).
from hdjoint.fmu.runner import (CONTROLLER_INPUTS, CONTROLLER_OUTPUTS, ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS,
    JOINT_INPUTS, JOINT_OUTPUTS)

ESTIMATOR = "JointTorqueEstimator"
JOINT = "HarmonicDriveJoint"
CONTROLLER = "JointController"
FMU_NAMES = (ESTIMATOR, JOINT)
ALL_FMUS = (ESTIMATOR, JOINT, CONTROLLER)
FMU_IO = {ESTIMATOR: (ESTIMATOR_INPUTS, ESTIMATOR_OUTPUTS), JOINT: (JOINT_INPUTS, JOINT_OUTPUTS),
          CONTROLLER: (CONTROLLER_INPUTS, CONTROLLER_OUTPUTS)}

_STATUS = ("OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING")


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: over ~5 s (diagnoses, JVMs, compiles, fuzz runs); runs by default, the fast lane deselects it with -m 'not slow'")


def pytest_report_header(config):
    return f"hdjoint imported from {Path(hdjoint.__file__).parent}"


@pytest.fixture(scope="session", autouse=True)
def _installed_package_is_used():
    # The tests must exercise the installed package, not python/ from the tree.
    here = Path(hdjoint.__file__).resolve()
    assert (TESTS_DIR.parent / "python") not in here.parents, (
        f"hdjoint was imported from the source tree ({here}); install it with pip install . and "
        "do not put python/ on sys.path")


# ---------------------------------------------------------------- FMUs


@pytest.fixture(scope="session")
def estimator_fmu() -> Path:
    return fmu_path(ESTIMATOR)


@pytest.fixture(scope="session")
def joint_fmu() -> Path:
    return fmu_path(JOINT)


@pytest.fixture(scope="session")
def unzipped(tmp_path_factory):
    """Each FMU extracted once per session: {model identifier: directory}."""
    root = tmp_path_factory.mktemp("fmus")
    return {name: Path(fmpy.extract(str(fmu_path(name)), str(root / name))) for name in ALL_FMUS}


# fmpy's logger proxy (which formats the FMU's printf-style message) keeps ONE
# Python logger in a C static: the last one registered. So every Slave
# registers the same module-level dispatcher, kept alive for the session, and
# messages are routed by the componentEnvironment each instance hands the FMU.
_SLAVE_MESSAGES: dict[int, list] = {}
_NEXT_ENVIRONMENT = [1]


def _dispatch(env, instance_name, status, category, message):
    messages = _SLAVE_MESSAGES.get(env or 0)
    entry = (_STATUS[status] if 0 <= status < len(_STATUS) else str(status), message.decode("utf-8", "replace"))
    if messages is None:  # an FMU that lost its environment: keep the message visible
        _SLAVE_MESSAGES.setdefault(0, []).append(entry)
    else:
        messages.append(entry)


_DISPATCHER = fmi2CallbackLoggerTYPE(_dispatch)


class Slave:
    """An FMU2Slave with a logger that records (status, message) tuples.

    Several Slaves built from the same unzipped directory share one loaded
    binary, which is what a master with many instances does.
    """

    def __init__(self, unzipdir: Path, instance_name: str = "instance", guid: str | None = None,
                 logging_on: bool = False, instantiate: bool = True):
        self.unzipdir = Path(unzipdir)
        self.description = fmpy.read_model_description(str(self.unzipdir))
        self.variables = {v.name: v for v in self.description.modelVariables}
        self.messages: list[tuple[str, str]] = []
        self.environment = _NEXT_ENVIRONMENT[0]
        _NEXT_ENVIRONMENT[0] += 1
        _SLAVE_MESSAGES[self.environment] = self.messages
        self._callbacks = fmi2CallbackFunctions()
        self._callbacks.logger = _DISPATCHER
        self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        self._callbacks.componentEnvironment = self.environment
        self.slave = FMU2Slave(guid=guid or self.description.guid, unzipDirectory=str(self.unzipdir),
                               modelIdentifier=self.description.coSimulation.modelIdentifier,
                               instanceName=instance_name)
        self._freed = True
        if instantiate:
            self.instantiate(logging_on)

    def callbacks(self) -> fmi2CallbackFunctions:
        """The callbacks, with fmpy's proxy pointed at the dispatcher (something else may have moved it)."""
        from fmpy.logging import addLoggerProxy
        self._callbacks.logger = _DISPATCHER
        addLoggerProxy(ctypes.byref(self._callbacks))
        return self._callbacks

    def instantiate(self, logging_on: bool = False):
        """fmi2Instantiate; fmpy raises when it returns NULL."""
        self.slave.instantiate(callbacks=self.callbacks(), loggingOn=logging_on)
        self._freed = False

    def errors(self) -> list[str]:
        return [m for s, m in self.messages if s in ("ERROR", "FATAL")]

    def vr(self, names) -> list[int]:
        return [self.variables[n].valueReference for n in names]

    def set(self, values: dict[str, float]):
        if values:
            self.slave.setReal(self.vr(values), [float(v) for v in values.values()])

    def get(self, names) -> np.ndarray:
        return np.array(self.slave.getReal(self.vr(names)))

    def start(self, params: dict[str, float] | None = None, inputs: dict[str, float] | None = None,
              start_time: float = 0.0, stop_time: float | None = None):
        self.slave.setupExperiment(None, start_time, stop_time)
        self.slave.enterInitializationMode()
        self.set(params or {})
        self.set(inputs or {})
        self.slave.exitInitializationMode()

    def run(self, t0: float, steps, inputs, input_names, output_names) -> np.ndarray:
        """Set row k of `inputs`, doStep(t, steps[k]), read outputs; returns the outputs per step."""
        vin, vout = self.vr(input_names), self.vr(output_names)
        out = np.empty((len(steps), len(output_names)))
        t = t0
        for k, h in enumerate(steps):
            self.slave.setReal(vin, [float(x) for x in inputs[k]])
            self.slave.doStep(t, float(h))
            out[k] = self.slave.getReal(vout)
            t += float(h)
        return out

    def free(self):
        if not self._freed:
            self._freed = True
            self.slave.freeInstance()


class Twin:
    """An FMI 3.0 Co-Simulation instance of a twin (fmpy's FMU3Slave) with its log messages recorded."""

    def __init__(self, name, tmp_path, instance_name: str = "twin", **instantiate):
        from fmpy.fmi3 import FMU3Slave
        self.unzipdir = fmpy.extract(str(fmu_path(name, 3)), str(tmp_path / f"{name}_3"))
        self.md = fmpy.read_model_description(self.unzipdir)
        self.vr = {v.name: v.valueReference for v in self.md.modelVariables}
        self.messages: list[str] = []
        self.slave = FMU3Slave(guid=self.md.guid, unzipDirectory=self.unzipdir,
                               modelIdentifier=self.md.coSimulation.modelIdentifier, instanceName=instance_name)
        self.slave.instantiate(logMessage=self._log, **instantiate)

    def _log(self, env, status, category, message):
        self.messages.append(message.decode())

    def refused(self, call, *args) -> str:
        """The message of CALL(*ARGS), which must fail."""
        with pytest.raises(Exception):
            call(*args)
        return self.messages[-1]

    def start(self, stop=None):
        self.slave.enterInitializationMode(startTime=0.0, stopTime=stop)
        self.slave.exitInitializationMode()

    def outputs(self):
        names = [v.name for v in self.md.modelVariables if v.causality == "output"]
        return np.array(self.slave.getFloat64([self.vr[n] for n in names]))


@pytest.fixture
def make_slave(unzipped):
    """Factory: make_slave(model_identifier, instance_name=...) -> Slave, freed at teardown."""
    made: list[Slave] = []

    def make(name: str, instance_name: str = "instance", **kw) -> Slave:
        s = Slave(unzipped[name], instance_name, **kw)
        made.append(s)
        return s

    yield make
    for s in reversed(made):
        s.free()


# ---------------------------------------------------------------- parameters and data


@pytest.fixture(scope="session")
def default_params() -> dict[str, float]:
    return parameters.defaults()


@pytest.fixture(scope="session")
def estimator_params(default_params) -> dict[str, float]:
    return parameters.for_estimator(default_params)


@pytest.fixture(scope="session")
def recording():
    """3 s of the paper experiment at 1 kHz (the joint FMU under closed-loop control)."""
    from hdjoint.fmu import experiments
    return experiments.run("paper", duration=3.0)


@pytest.fixture
def recording_csv(recording, tmp_path) -> Path:
    from hdjoint.io.recording import write_recording
    path = tmp_path / "rec.csv"
    write_recording(path, recording)
    return path


def joint_test_inputs(n: int, dt: float = 1e-3, seed: int = 3) -> np.ndarray:
    """Open-loop joint inputs (i_m, tau_ext): current steps and a sinusoid, small load."""
    t = np.arange(n) * dt
    rng = np.random.default_rng(seed)
    i_m = 0.8 * np.sin(2 * np.pi * 2.0 * t) + 0.5 * (t > 0.1) + 0.05 * rng.standard_normal(n)
    tau_ext = 0.3 * np.sin(2 * np.pi * 0.7 * t)
    return np.column_stack([i_m, tau_ext])


# ---------------------------------------------------------------- fleet
# Here, not in tests/fleet/conftest.py: a second module named `conftest`
# would shadow this one for the tests that import names from it.
FLEET_ALLOWED_FAILURES = 1  # a recording that kills its worker twice is marked failed


@pytest.fixture(scope="session")
def fleet_client():
    """A real dask.distributed LocalCluster with 2 worker processes, shared by the fleet tests."""
    from hdjoint.fleet.run import connect
    client = connect(None, 2, FLEET_ALLOWED_FAILURES)
    yield client
    cluster = client.cluster
    client.close()
    cluster.close()


@pytest.fixture
def two_workers(fleet_client):
    """The client once both workers are up (a killed one is restarted by its nanny)."""
    fleet_client.wait_for_workers(2, timeout=120)
    return fleet_client
