"""Run the project's FMUs through fmpy.

`FmuInstance` wraps fmpy's FMU2Slave for step-by-step use: the FMU's log
messages are captured (so an fmi2Error surfaces with the FMU's own words), and
the per-step calls go through preallocated ctypes arrays because a recording
means tens of thousands of steps.
"""
from __future__ import annotations

import ctypes
import itertools
import os
import shutil
import tempfile
from pathlib import Path

import numpy as np
from fmpy import extract, read_model_description
from fmpy.fmi2 import FMU2Slave, fmi2CallbackFunctions, fmi2CallbackLoggerTYPE, fmi2CallbackAllocateMemoryTYPE, \
    fmi2CallbackFreeMemoryTYPE
from fmpy.fmi1 import FMICallException
from fmpy import calloc, free

from hdjoint import _core
from hdjoint.fmu.shipped import fmu_path
from hdjoint.io.outputs import sweep_temp_dirs


def _signal_names(model: str, kind: str) -> tuple[str, ...]:
    """An FMU's inputs or outputs in value-reference order, from its C++ signal table."""
    return tuple(row["name"] for row in _core.fmu_signals()[model] if row["kind"] == kind)


# Declared once, in src/hdjoint/*_signals.def; read here through the bindings.
ESTIMATOR_INPUTS = _signal_names("JointTorqueEstimator", "input")
ESTIMATOR_OUTPUTS = _signal_names("JointTorqueEstimator", "output")
JOINT_INPUTS = _signal_names("HarmonicDriveJoint", "input")
JOINT_OUTPUTS = _signal_names("HarmonicDriveJoint", "output")
CONTROLLER_INPUTS = _signal_names("JointController", "input")
CONTROLLER_OUTPUTS = _signal_names("JointController", "output")
_STATUS = ["OK", "WARNING", "DISCARD", "ERROR", "FATAL", "PENDING"]


class FmuError(RuntimeError):
    """An FMU call failed; the message carries what the FMU logged."""


# fmpy's logger proxy (which formats the FMU's printf-style message) keeps ONE
# Python logger in a C static: the last one registered. Every instance
# therefore registers this one module-level dispatcher, alive for the whole
# process, and messages are routed by the componentEnvironment each instance
# hands its FMU. (A per-instance logger would send one instance's messages
# to another, and crash once the registered instance was freed.)
_MESSAGES: dict[int, list] = {}
_ENVIRONMENTS = itertools.count(1)


def _dispatch(env, instance_name, status, category, message):
    entry = (_STATUS[status] if 0 <= status < len(_STATUS) else str(status), message.decode("utf-8", "replace"))
    _MESSAGES.setdefault(env or 0, []).append(entry)


_DISPATCHER = fmi2CallbackLoggerTYPE(_dispatch)


class FmuInstance:
    """One instance of an FMU, driven step by step."""

    def __init__(self, fmu: str | Path, instance_name: str = "instance", logging_on: bool = False):
        self.path = Path(fmu)
        self.description = read_model_description(str(self.path))
        self.variables = {v.name: v for v in self.description.modelVariables}
        # Only what running needs: the FMU also carries its sources (with Eigen).
        # Into a folder named with the pid: a run killed outright leaves it, and the next run removes it.
        sweep_temp_dirs("hdjoint-fmu")
        unzipdir = tempfile.mkdtemp(prefix=f"hdjoint-fmu-{os.getpid()}-")
        try:
            self._unzipdir = extract(str(self.path), unzipdir=unzipdir,
                                     include=lambda name: not name.startswith("sources/"))
        except BaseException as e:  # a full temporary folder, memory
            shutil.rmtree(unzipdir, ignore_errors=True)
            if isinstance(e, OSError):
                raise OSError(e.errno, f"cannot unpack {self.path.name} into {unzipdir} (TMPDIR): "
                                       f"{e.strerror}") from None
            raise
        try:  # any failure from here (memory too) removes the unpacked FMU
            self.messages: list[tuple[str, str]] = []  # (status, message)
            self._environment = next(_ENVIRONMENTS)
            _MESSAGES[self._environment] = self.messages
            self._callbacks = fmi2CallbackFunctions()
            self._callbacks.logger = _DISPATCHER
            self._callbacks.componentEnvironment = self._environment
            self._callbacks.allocateMemory = fmi2CallbackAllocateMemoryTYPE(calloc)
            self._callbacks.freeMemory = fmi2CallbackFreeMemoryTYPE(free)
            try:
                from fmpy.logging import addLoggerProxy  # formats the printf-style message in C
                addLoggerProxy(ctypes.byref(self._callbacks))
            except Exception:  # pragma: no cover - fmpy without its logging helper
                pass
            self.slave = FMU2Slave(guid=self.description.guid, unzipDirectory=self._unzipdir,
                                   modelIdentifier=self.description.coSimulation.modelIdentifier,
                                   instanceName=instance_name)
            self.slave.instantiate(callbacks=self._callbacks, loggingOn=logging_on)
            self._terminated = False
        except BaseException:
            _MESSAGES.pop(getattr(self, "_environment", None), None)
            shutil.rmtree(unzipdir, ignore_errors=True)
            raise

    def last_error(self) -> str:
        for status, message in reversed(self.messages):
            if status in ("ERROR", "FATAL", "WARNING"):
                return message
        return "no message logged"

    def call(self, what: str, fn, *args):
        """Call an fmpy wrapper, turning a failed FMI call into FmuError with the FMU's message."""
        try:
            return fn(*args)
        except FMICallException as e:
            raise FmuError(f"{self.path.name}: {what}: {self.last_error().removeprefix(what + ': ')}") from e

    def value_references(self, names) -> list[int]:
        missing = [n for n in names if n not in self.variables]
        if missing:
            raise KeyError(f"{self.path.name} has no variable(s) {', '.join(missing)}")
        return [self.variables[n].valueReference for n in names]

    def start(self, start_time: float = 0.0, stop_time: float | None = None,
              parameters: dict[str, float] | None = None, inputs: dict[str, float] | None = None):
        """setupExperiment, parameters and start inputs, initialization."""
        s = self.slave
        self.call("fmi2SetupExperiment", s.setupExperiment, None, start_time, stop_time)
        self.call("fmi2EnterInitializationMode", s.enterInitializationMode)
        for values in (parameters or {}, inputs or {}):
            if values:
                self.call("fmi2SetReal", s.setReal, self.value_references(values), list(values.values()))
        self.call("fmi2ExitInitializationMode", s.exitInitializationMode)

    def stepper(self, inputs, outputs) -> "Stepper":
        return Stepper(self, inputs, outputs)

    def get(self, names) -> list[float]:
        return self.call("fmi2GetReal", self.slave.getReal, self.value_references(names))

    def close(self):
        if not self._terminated:
            self._terminated = True
            try:
                try:
                    self.slave.terminate()
                except Exception:
                    pass
                self.slave.freeInstance()
            finally:
                _MESSAGES.pop(self._environment, None)
                shutil.rmtree(self._unzipdir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


class Stepper:
    """Fast set-inputs / doStep / get-outputs straight through the binary's
    FMI functions (fmpy's wrappers cost several microseconds a call, which
    is most of the time on a long recording)."""

    def __init__(self, instance: FmuInstance, inputs, outputs):
        self.instance = instance
        self._component = instance.slave.component
        dll = instance.slave.dll
        # dll[name] gives a fresh function object: fmpy's own prototypes stay untouched.
        self._set_real, self._do_step, self._get_real = dll["fmi2SetReal"], dll["fmi2DoStep"], dll["fmi2GetReal"]
        array_args = [ctypes.c_void_p, ctypes.POINTER(ctypes.c_uint), ctypes.c_size_t, ctypes.POINTER(ctypes.c_double)]
        for fn in (self._set_real, self._get_real):
            fn.argtypes, fn.restype = array_args, ctypes.c_int
        self._do_step.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_double, ctypes.c_int]
        self._do_step.restype = ctypes.c_int
        self._in_vr = (ctypes.c_uint * len(inputs))(*instance.value_references(inputs))
        self._out_vr = (ctypes.c_uint * len(outputs))(*instance.value_references(outputs))
        self._in = (ctypes.c_double * len(inputs))()
        self._out = (ctypes.c_double * len(outputs))()
        self._n_in, self._n_out = len(inputs), len(outputs)

    def step(self, t: float, h: float, values) -> ctypes.Array:
        """Set inputs, step [t, t+h), return the outputs array (reused).
        Warnings are logged by the FMU and let through; errors raise FmuError."""
        self._in[:] = values
        c = self._component
        if (self._set_real(c, self._in_vr, self._n_in, self._in) > 1
                or self._do_step(c, t, h, 1) > 1
                or self._get_real(c, self._out_vr, self._n_out, self._out) > 1):
            raise FmuError(f"{self.instance.path.name}: at t = {t!r} s: {self.instance.last_error()}")
        return self._out


def run_estimator_fmu(time, i_m, theta_m, theta_l, params: dict[str, float] | None = None,
                      fmu: str | Path | None = None, outputs=ESTIMATOR_OUTPUTS,
                      warnings: list[str] | None = None) -> dict[str, np.ndarray]:
    """JointTorqueEstimator.fmu over a recording's samples; the FMU's
    fmi2Warning messages are appended to `warnings` when given.

    Row j is a communication point: its inputs are set, the FMU steps to the
    next row's time (the last row by Ts), and row j's outputs are read after the step.
    """
    time = np.asarray(time, float)
    n = len(time)
    params = params or {}
    from hdjoint.io.parameters import table
    ts = params.get("Ts", table()["Ts"].default)
    result = np.empty((n, len(outputs)))
    with FmuInstance(fmu or fmu_path("JointTorqueEstimator"), "estimator") as inst:
        inst.start(float(time[0]), None, params, {"i_m": float(i_m[0]), "theta_m": float(theta_m[0]),
                                                  "theta_l": float(theta_l[0])})
        stepper = inst.stepper(ESTIMATOR_INPUTS, outputs)
        steps = np.append(np.diff(time), ts)
        columns = np.column_stack([i_m, theta_m, theta_l]).tolist()
        for j in range(n):
            result[j] = stepper.step(float(time[j]), float(steps[j]), columns[j])
        if warnings is not None:
            warnings.extend(message for status, message in inst.messages if status == "WARNING")
    return {name: result[:, k].copy() for k, name in enumerate(outputs)}
