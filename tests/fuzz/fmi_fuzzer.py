"""A call-sequence fuzzer for the project's FMUs: FMI 2.0 and FMI 3.0,
Co-Simulation and (the joint) Model Exchange.

Each sequence runs in a forked child process (the FMU's binary is loaded
once in the parent, so a child starts in milliseconds); a child that dies is
a crash, one that outlives its time budget is a hang. The budget is the
child's CPU time (an ITIMER_PROF timer: SIGPROF's default action kills it), so
a loaded machine, which slows the wall clock, cannot fake a hang; a wall-clock
backstop (BACKSTOP_FACTOR times the budget) catches a child that blocks
without computing. Inside the child a
model of the FMI 2.0 state machine (the co-simulation state table) says
whether each call is legal (one table per FMI version and interface: the
same call names -- "setup", "enter", "step", "settime", ... -- map to each
version's functions), so the fuzzer can tell:

    crash                     the child died on a signal or exited abnormally
    hang                      the sequence used more than its CPU budget, or
                              made no progress within the wall-clock backstop
    illegal call accepted     a call the standard forbids (wrong state, bad
                              value, wrong communication point, a step past
                              stopTime) returned fmi2OK/Warning/Discard
    corrupted state accepted  a truncated, extended or foreign serialised
                              state, or one with a non-finite field or an
                              edited field (any value changed: the state
                              is sealed by a CRC-32), was deserialised (or
                              set) with success
    non-finite output         fmi2GetReal returned fmi2OK with NaN or Inf
                              outside the error state

Sequences are generated from (FMU, seed) and recorded as explicit call
lists, so any finding replays with `replay` and shrinks with `minimise`.
"""
from __future__ import annotations

import ctypes
import faulthandler
import json
import math
import os
import random
import select
import signal
import struct
import tempfile
import time
from collections import Counter
from dataclasses import dataclass, field
from pathlib import Path

import fmpy
from fmpy.fmi2 import (FMU2Model, FMU2Slave, fmi2CallbackAllocateMemoryTYPE, fmi2CallbackFreeMemoryTYPE,
                       fmi2CallbackFunctions, fmi2CallbackLoggerTYPE)
from fmpy.fmi3 import FMU3Model, FMU3Slave, fmi3LogMessageCallback

CATEGORIES = ("crash", "hang", "illegal call accepted", "corrupted state accepted", "non-finite output")
OK, WARNING, DISCARD, ERROR, FATAL = range(5)

# The FMI 2.0 co-simulation states (fmi2 standard, section 4.2.4).
INSTANTIATED, INIT, STEP_COMPLETE, STEP_FAILED, TERMINATED, ERROR_STATE, FATAL_STATE = (
    "instantiated", "initialization mode", "step complete", "step failed", "terminated", "error", "fatal")
NOT_FATAL = {INSTANTIATED, INIT, STEP_COMPLETE, STEP_FAILED, TERMINATED, ERROR_STATE}
# Where each call is allowed (the standard's state table); anything else is illegal.
ALLOWED = {
    "setup": {INSTANTIATED},
    "enter": {INSTANTIATED},
    "exit": {INIT},
    "terminate": {STEP_COMPLETE, STEP_FAILED},
    "reset": NOT_FATAL,
    "get": {INIT, STEP_COMPLETE, STEP_FAILED, TERMINATED, ERROR_STATE},
    "set": {INSTANTIATED, INIT, STEP_COMPLETE},
    "step": {STEP_COMPLETE},
    "status": {STEP_COMPLETE, STEP_FAILED, TERMINATED},
    "getstate": NOT_FATAL, "setstate": NOT_FATAL, "freestate": NOT_FATAL,
    "serialize": NOT_FATAL, "deserialize": NOT_FATAL,
}
# Model Exchange's calls (FMI 2.0 section 3.2.3, FMI 3.0 section 3.2): illegal in Co-Simulation.
EVENT, CT = "event mode", "continuous-time mode"
ME_CALLS = ("enterct", "enterevent", "update", "completed", "settime", "setx", "getx", "getdx", "getz")
ALLOWED.update({call: set() for call in ME_CALLS})
ALLOWED_ME = {
    **ALLOWED,
    "terminate": {EVENT, CT},
    "reset": NOT_FATAL | {EVENT, CT},
    "get": {INIT, EVENT, CT, TERMINATED, ERROR_STATE},
    "set": {INSTANTIATED, INIT, EVENT, CT},
    "step": set(), "status": set(),
    **{call: NOT_FATAL | {EVENT, CT} for call in ("getstate", "setstate", "freestate", "serialize", "deserialize")},
    "enterct": {EVENT}, "enterevent": {CT}, "update": {EVENT}, "completed": {CT},
    "settime": {EVENT, CT}, "setx": {CT}, "getx": {INIT, EVENT, CT, TERMINATED},
    "getdx": {INIT, EVENT, CT, TERMINATED}, "getz": {INIT, EVENT, CT, TERMINATED},
}
# FMI 3.0 (no separate setup: "setup" only notes the times "enter" passes; "status" is
# fmi3EnterConfigurationMode, illegal for an FMU without structural parameters).
ALLOWED_3 = {**ALLOWED, "setup": NOT_FATAL, "status": set(),
             "get": ALLOWED["get"] | {INSTANTIATED}}
ALLOWED_3_ME = {**ALLOWED_ME, "setup": NOT_FATAL | {EVENT, CT}, "get": ALLOWED_ME["get"] | {INSTANTIATED}}
TABLES = {(2, False): ALLOWED, (2, True): ALLOWED_ME, (3, False): ALLOWED_3, (3, True): ALLOWED_3_ME}
# Where the standard's wording leaves doubt: neither accepting nor refusing is a finding.
UNSETTLED = {"status": {INIT}}
# Serialised layout (fmu/fmi2_glue.cpp): doubles, sealed by a CRC-32 in the last one.
STATE_SLOT = 2  # header: magic, version, state, time, start, stop, stop-defined, count
# A sequence may take this many times its CPU budget in wall-clock time before the
# parent gives up on it (a child that blocks without computing): generous, so that
# only the CPU budget decides on a machine loaded up to ~BACKSTOP_FACTOR runnable processes a core.
BACKSTOP_FACTOR = 30

LEGAL_STEPS = (1e-3, 2e-3, 1e-2, 0.1)


def legal_times(start, stop) -> bool:
    """An experiment's times: a finite start, and no stop time or a finite one at or after it (an infinite
    stop time could not be saved in an FMU state and restored)."""
    return math.isfinite(start) and (stop is None or (math.isfinite(stop) and stop >= start))
EXTREME_STEPS = (215.0, 1e5, 2.2e5, 1e6, 1e300)
BAD_NUMBERS = (math.nan, math.inf, -math.inf)
FMU_NAMES = ("JointTorqueEstimator", "HarmonicDriveJoint", "JointController")


@dataclass
class Variable:
    name: str
    vr: int
    causality: str
    start: float
    min: float
    max: float


class LoadedFmu:
    """An FMU extracted and its binary loaded, in the parent, ready to fork from; instantiated
    for Model Exchange when MODEL_EXCHANGE (its name then ends in "_me")."""

    def __init__(self, path: Path, workdir: Path, model_exchange: bool = False):
        self.path = Path(path)
        self.model_exchange = model_exchange
        self.name = self.path.stem + ("_me" if model_exchange else "")
        self.unzipdir = fmpy.extract(str(self.path), str(Path(workdir) / self.name),
                                     include=lambda n: not n.startswith("sources/"))
        md = fmpy.read_model_description(self.unzipdir)
        self.fmi = 3 if md.fmiVersion.startswith("3") else 2
        self.allowed = TABLES[(self.fmi, model_exchange)]
        self.n_states = md.numberOfContinuousStates if model_exchange else 0
        self.n_indicators = md.numberOfEventIndicators if model_exchange else 0
        self.foreign_names: list[str] = []  # the other loaded FMUs (set by Campaign.load)
        self.guid = md.guid
        self.identifier = md.coSimulation.modelIdentifier
        self.variables = [Variable(v.name, v.valueReference, v.causality,
                                   float(v.start) if v.start is not None else 0.0,
                                   float(v.min) if v.min is not None else -math.inf,
                                   float(v.max) if v.max is not None else math.inf)
                          for v in md.modelVariables if v.causality != "independent"]
        self.outputs = [v for v in self.variables if v.causality == "output"]
        self.settable = [v for v in self.variables if v.causality in ("input", "parameter")]
        kind = {(2, False): FMU2Slave, (2, True): FMU2Model, (3, False): FMU3Slave, (3, True): FMU3Model}
        self.slave = kind[(self.fmi, model_exchange)](guid=self.guid, unzipDirectory=self.unzipdir,
                                                      modelIdentifier=self.identifier, instanceName="fuzz")
        self.dll = self.slave.dll
        self.ts = next((v.start for v in self.variables if v.name == "Ts"), 1e-3)
        self.serialised_sample: bytes = b""  # an initialised state, given to the OTHER FMUs as foreign


def _messages_logger(messages: list, fmi: int):
    if fmi == 3:
        def log3(env, status, category, message):
            messages.append(message.decode("utf-8", "replace"))
        return fmi3LogMessageCallback(log3)

    def log(env, instance, status, category, message):
        messages.append(message.decode("utf-8", "replace"))
    return fmi2CallbackLoggerTYPE(log)


_c, _d, _sz = ctypes.c_void_p, ctypes.c_double, ctypes.c_size_t
_i, _b, _pd = ctypes.c_int, ctypes.c_bool, ctypes.POINTER(ctypes.c_double)
_pu, _pc = ctypes.POINTER(ctypes.c_uint), ctypes.POINTER(ctypes.c_void_p)
# Each version's functions (without the fmi2/fmi3 prefix) and their arguments.
SIGNATURES = {
    2: {"SetupExperiment": [_c, _i, _d, _d, _i, _d], "EnterInitializationMode": [_c],
        "ExitInitializationMode": [_c], "Terminate": [_c], "Reset": [_c],
        "GetReal": [_c, _pu, _sz, _pd], "SetReal": [_c, _pu, _sz, _pd], "DoStep": [_c, _d, _d, _i],
        "GetFMUstate": [_c, _pc], "SetFMUstate": [_c, _c], "FreeFMUstate": [_c, _pc],
        "SerializedFMUstateSize": [_c, _c, ctypes.POINTER(_sz)], "SerializeFMUstate": [_c, _c, ctypes.c_char_p, _sz],
        "DeSerializeFMUstate": [_c, ctypes.c_char_p, _sz, _pc],
        "GetRealStatus": [_c, _i, _pd], "GetBooleanStatus": [_c, _i, ctypes.POINTER(_i)],
        "GetStatus": [_c, _i, ctypes.POINTER(_i)],
        "EnterContinuousTimeMode": [_c], "EnterEventMode": [_c], "NewDiscreteStates": [_c, ctypes.c_char_p],
        "CompletedIntegratorStep": [_c, _i, ctypes.POINTER(_i), ctypes.POINTER(_i)], "SetTime": [_c, _d],
        "SetContinuousStates": [_c, _pd, _sz], "GetContinuousStates": [_c, _pd, _sz],
        "GetDerivatives": [_c, _pd, _sz], "GetEventIndicators": [_c, _pd, _sz]},
    3: {"EnterInitializationMode": [_c, _b, _d, _d, _b, _d], "ExitInitializationMode": [_c], "Terminate": [_c],
        "Reset": [_c], "GetFloat64": [_c, _pu, _sz, _pd, _sz], "SetFloat64": [_c, _pu, _sz, _pd, _sz],
        "DoStep": [_c, _d, _d, _b, ctypes.POINTER(_b), ctypes.POINTER(_b), ctypes.POINTER(_b), _pd],
        "GetFMUState": [_c, _pc], "SetFMUState": [_c, _c], "FreeFMUState": [_c, _pc],
        "SerializedFMUStateSize": [_c, _c, ctypes.POINTER(_sz)], "SerializeFMUState": [_c, _c, ctypes.c_char_p, _sz],
        "DeserializeFMUState": [_c, ctypes.c_char_p, _sz, _pc], "EnterConfigurationMode": [_c],
        "EnterContinuousTimeMode": [_c], "EnterEventMode": [_c],
        "UpdateDiscreteStates": [_c] + [ctypes.POINTER(_b)] * 5 + [_pd],
        "CompletedIntegratorStep": [_c, _b, ctypes.POINTER(_b), ctypes.POINTER(_b)], "SetTime": [_c, _d],
        "SetContinuousStates": [_c, _pd, _sz], "GetContinuousStates": [_c, _pd, _sz],
        "GetContinuousStateDerivatives": [_c, _pd, _sz], "GetEventIndicators": [_c, _pd, _sz]},
}
# FMI 2.0 names of the calls whose FMI 3.0 name differs.
FMI3_NAMES = {"GetReal": "GetFloat64", "SetReal": "SetFloat64", "GetFMUstate": "GetFMUState",
              "SetFMUstate": "SetFMUState", "FreeFMUstate": "FreeFMUState",
              "SerializedFMUstateSize": "SerializedFMUStateSize", "SerializeFMUstate": "SerializeFMUState",
              "DeSerializeFMUstate": "DeserializeFMUState", "GetDerivatives": "GetContinuousStateDerivatives"}


class Calls:
    """The FMI functions of one binary with raw statuses (fmpy's wrappers raise instead), by their
    FMI 2.0 names without the prefix (calls.GetReal is fmi3GetFloat64 in an FMI 3.0 binary)."""

    def __init__(self, dll, fmi: int = 2):
        self.fmi = fmi
        self.f = {}
        for name, args in SIGNATURES[fmi].items():
            fn = dll[f"fmi{fmi}{name}"]
            fn.argtypes, fn.restype = args, ctypes.c_int
            self.f[name] = fn

    def __getattr__(self, name):
        return self.f[FMI3_NAMES.get(name, name) if self.fmi == 3 else name]


@dataclass
class Snapshot:
    """What the model knows of a saved state: the FMI state, time and stop time (None: unknown)."""
    state: str | None
    time: float | None
    stop: float | None


@dataclass
class Model:
    """The fuzzer's view of one instance."""
    state: str = INSTANTIATED
    time: float = 0.0
    stop: float | None = None
    start: float = 0.0
    tainted: bool = False  # after an accepted illegal call or an unchecked state: legality unknown


class Child:
    """Runs one sequence (in the forked child), reporting each call before it is made."""

    def __init__(self, fmu: LoadedFmu, foreign: dict[str, bytes], report):
        self.fmu, self.foreign, self.report = fmu, foreign, report
        self.calls = Calls(fmu.dll, fmu.fmi)
        self.messages: list[str] = []
        self._logger = _messages_logger(self.messages, fmu.fmi)
        self._pending = (0.0, None)  # FMI 3.0: the times "enter" passes
        self._x: list[float] | None = None  # Model Exchange: the states last read
        self.component = None
        self.model = Model()
        self.handles: dict[int, tuple[ctypes.c_void_p, Snapshot]] = {}
        self.blobs: dict[int, tuple[bytes, Snapshot]] = {}
        self._pending_findings: list = []
        self._last_values: dict = {}

    # -- the instance --------------------------------------------------------------------
    def instantiate(self):
        if self.fmu.fmi == 3:
            self.fmu.slave.instantiate(logMessage=lambda env, status, category, message:
                                       self.messages.append(message.decode("utf-8", "replace")))
            self.component = self.fmu.slave.component
            self.model = Model()
            self.handles.clear()
            return
        cb = fmi2CallbackFunctions()
        cb.logger = self._logger
        cb.allocateMemory = fmi2CallbackAllocateMemoryTYPE(fmpy.calloc)
        cb.freeMemory = fmi2CallbackFreeMemoryTYPE(fmpy.free)
        try:
            from fmpy.logging import addLoggerProxy
            addLoggerProxy(ctypes.byref(cb))
        except Exception:
            pass
        self._callbacks = cb
        self.fmu.slave.instantiate(callbacks=cb)
        self.component = self.fmu.slave.component
        self.model = Model()
        self.handles.clear()  # handles of a freed instance are gone; serialised bytes survive

    def free(self):
        # Not fmpy's freeInstance: it also unloads the binary, which later calls still use.
        getattr(self.fmu.slave, f"fmi{self.fmu.fmi}FreeInstance")(self.component)
        self.component = None

    # -- one call ----------------------------------------------------------------------
    def run(self, op: list):
        """Make one call; returns [(category, detail)] findings."""
        kind = op[0]
        if kind == "instantiate":
            if self.component is None:
                self.instantiate()
            return []
        if self.component is None:
            return []
        if kind == "free":
            self.free()
            return []
        if kind == "_selftest":  # the harness's own check: a crash or a hang it must classify
            _selftest(op[1], op[2])
            return []
        m = self.model
        if m.state == FATAL_STATE:
            return []
        legal = m.state in self.fmu.allowed[kind]
        findings = []
        if m.state in UNSETTLED.get(kind, ()):
            legal = None
        status, extra = getattr(self, "_" + kind)(op, legal)
        if status is None:  # nothing to call (e.g. no saved state in that slot)
            return []
        if extra is not None and legal is not None:
            legal = legal and extra
        accepted = status < ERROR
        if not m.tainted and legal is False and accepted:
            findings.append(("illegal call accepted", f"{op} in state '{m.state}' returned {status}"))
            m.tainted = True
        if status >= FATAL:
            m.state = FATAL_STATE
        elif status >= ERROR:
            m.state = ERROR_STATE
        elif kind in ("get", "getx", "getdx", "getz") and status == OK and m.state != ERROR_STATE:
            bad = [n for n, v in self._last_values.items() if not math.isfinite(v)]
            if bad:
                findings.append(("non-finite output", f"{op}: {bad} after fmi2OK in state '{m.state}'"))
        self._after(op, status)
        findings.extend(self._pending_findings)
        self._pending_findings = []
        return findings

    def _after(self, op, status):
        m, kind = self.model, op[0]
        if status >= ERROR:
            return
        if kind == "setup" and self.fmu.fmi == 2:
            m.start, m.stop = op[1], op[2]
            m.time = m.start
        elif kind == "enter":
            m.state = INIT
            if self.fmu.fmi == 3:
                m.start, m.stop = self._pending
                m.time = m.start
        elif kind == "exit":
            m.state = EVENT if self.fmu.model_exchange else STEP_COMPLETE
        elif kind == "enterct":
            m.state = CT
        elif kind == "enterevent":
            m.state = EVENT
        elif kind == "settime":
            m.time = op[1]
        elif kind == "terminate":
            m.state = TERMINATED
        elif kind == "reset":
            m.__init__()
            self._pending = (0.0, None)
        elif kind == "step":
            if status == DISCARD:
                m.state = STEP_FAILED
            else:
                m.time = op[1] + op[2]

    def _vr(self, names):
        index = {v.name: v for v in self.fmu.variables}
        return [index[n].vr if n in index else int(n) for n in names]

    def _setup(self, op, legal):
        start, stop = op[1], op[2]
        ok = legal_times(start, stop)
        if self.fmu.fmi == 3:  # the times go with fmi3EnterInitializationMode
            if self.model.state == INSTANTIATED:
                self._pending = (start, stop)
            return None, None
        return self.calls.SetupExperiment(self.component, 0, 0.0, start, int(stop is not None),
                                          0.0 if stop is None else stop), ok

    def _enter(self, op, legal):
        if self.fmu.fmi == 2:
            return self.calls.EnterInitializationMode(self.component), None
        start, stop = self._pending
        ok = legal_times(start, stop)
        return self.calls.EnterInitializationMode(self.component, False, 0.0, start, stop is not None,
                                                  0.0 if stop is None else stop), ok

    def _exit(self, op, legal):
        return self.calls.ExitInitializationMode(self.component), None

    def _terminate(self, op, legal):
        return self.calls.Terminate(self.component), None

    def _reset(self, op, legal):
        return self.calls.Reset(self.component), None

    def _get(self, op, legal):
        names = op[1]
        vr = (ctypes.c_uint * len(names))(*self._vr(names))
        out = (ctypes.c_double * len(names))()
        status = self.calls.GetReal(self.component, vr, len(names), out, *self._n(len(names)))
        self._last_values = dict(zip(names, out))
        return status, all(isinstance(n, str) for n in names)

    def _set(self, op, legal):
        name, value = op[1], op[2]
        var = next((v for v in self.fmu.variables if v.name == name), None)
        vr = (ctypes.c_uint * 1)(var.vr if var else int(name))
        status = self.calls.SetReal(self.component, vr, 1, (ctypes.c_double * 1)(value), *self._n(1))
        ok = (var is not None and var.causality in ("input", "parameter") and math.isfinite(value)
              and var.min <= value <= var.max
              and (var.causality == "input" or self.model.state in (INSTANTIATED, INIT)))
        return status, ok

    def _step(self, op, legal):
        t, h = op[1], op[2]
        if self.fmu.fmi == 3:
            flags, last = [ctypes.c_bool() for _ in range(3)], ctypes.c_double()
            status = self.calls.DoStep(self.component, t, h, True, *map(ctypes.byref, flags), ctypes.byref(last))
        else:
            status = self.calls.DoStep(self.component, t, h, 1)
        m = self.model
        if not (math.isfinite(t) and math.isfinite(h)) or not h > 0:  # the step size must be > 0 (0 and -0 too)
            return status, False
        off = abs(t - m.time)
        if off > 1e-6 * max(1.0, abs(m.time)):
            return status, False
        if m.stop is not None and t + h > m.stop * (1 + 1e-6) + 1e-6 + 1e-3 * h:
            return status, False
        return status, True

    def _n(self, n):
        """FMI 3.0's get and set take the number of values too."""
        return (n,) if self.fmu.fmi == 3 else ()

    def _status(self, op, legal):
        if self.fmu.fmi == 3:
            return self.calls.EnterConfigurationMode(self.component), None
        which = op[1]
        if which == "real":
            return self.calls.GetRealStatus(self.component, 2, ctypes.byref(ctypes.c_double())), None
        if which == "boolean":
            return self.calls.GetBooleanStatus(self.component, 3, ctypes.byref(ctypes.c_int())), None
        return self.calls.GetStatus(self.component, 0, ctypes.byref(ctypes.c_int())), None

    # -- Model Exchange -------------------------------------------------------------------
    def _enterct(self, op, legal):
        return self.calls.EnterContinuousTimeMode(self.component), None

    def _enterevent(self, op, legal):
        return self.calls.EnterEventMode(self.component), None

    def _update(self, op, legal):
        if self.fmu.fmi == 2:
            return self.calls.NewDiscreteStates(self.component, ctypes.create_string_buffer(64)), None
        flags, next_time = [ctypes.c_bool() for _ in range(5)], ctypes.c_double()
        return self.calls.UpdateDiscreteStates(self.component, *map(ctypes.byref, flags),
                                               ctypes.byref(next_time)), None

    def _completed(self, op, legal):
        flag = ctypes.c_bool if self.fmu.fmi == 3 else ctypes.c_int
        a, b = flag(), flag()
        return self.calls.CompletedIntegratorStep(self.component, 1, ctypes.byref(a), ctypes.byref(b)), None

    def _settime(self, op, legal):
        t = op[1]
        return self.calls.SetTime(self.component, t), math.isfinite(t) and t >= self.model.start

    def _setx(self, op, legal):
        """["setx", factor, index, value, size change]: the states last read times (1 + factor),
        with VALUE at INDEX (none: None), as n + SIZE CHANGE values."""
        factor, index, bad, delta = op[1], op[2], op[3], op[4]
        n = self.fmu.n_states
        values = [x * (1.0 + factor) for x in (self._x or [0.0] * n)]
        if index is not None and n:
            values[index % n] = bad
        count = max(0, n + delta)
        array = (ctypes.c_double * max(count, 1))(*(values + [0.0] * count)[:max(count, 1)])
        status = self.calls.SetContinuousStates(self.component, array, count)
        return status, delta == 0 and all(math.isfinite(v) for v in values)

    def _vector(self, op, function, n):
        count = max(0, n + op[1])
        array = (ctypes.c_double * max(count, 1))()
        status = getattr(self.calls, function)(self.component, array, count)
        values = list(array)[:count]
        self._last_values = {f"{function}[{k}]": v for k, v in enumerate(values)}
        return status, values, op[1] == 0

    def _getx(self, op, legal):
        status, values, ok = self._vector(op, "GetContinuousStates", self.fmu.n_states)
        if status == OK and ok:
            self._x = values
        return status, ok

    def _getdx(self, op, legal):
        status, _, ok = self._vector(op, "GetDerivatives", self.fmu.n_states)
        return status, ok

    def _getz(self, op, legal):
        status, _, ok = self._vector(op, "GetEventIndicators", self.fmu.n_indicators)
        return status, ok

    def _snapshot(self) -> Snapshot:
        m = self.model
        if m.tainted:
            return Snapshot(None, None, None)
        return Snapshot(m.state, m.time, m.stop)

    def _getstate(self, op, legal):
        handle = ctypes.c_void_p()
        status = self.calls.GetFMUstate(self.component, ctypes.byref(handle))
        if status < ERROR:
            old = self.handles.pop(op[1], None)
            if old is not None:
                self.calls.FreeFMUstate(self.component, ctypes.byref(old[0]))
            self.handles[op[1]] = (handle, self._snapshot())
        return status, None

    def _restore(self, snap: Snapshot):
        m = self.model
        if snap.state is None:
            m.tainted = True
        else:
            m.state, m.time, m.stop = snap.state, snap.time, snap.stop

    def _setstate(self, op, legal):
        entry = self.handles.get(op[1])
        if entry is None:
            return None, None  # nothing to set: not called (a null state is the host's bug)
        status = self.calls.SetFMUstate(self.component, entry[0])
        if status < ERROR:
            self._restore(entry[1])
        return status, None

    def _freestate(self, op, legal):
        entry = self.handles.pop(op[1], None)
        if entry is None:
            return None, None
        return self.calls.FreeFMUstate(self.component, ctypes.byref(entry[0])), None

    def _serialize(self, op, legal):
        entry = self.handles.get(op[1])
        if entry is None:
            return None, None
        size = ctypes.c_size_t()
        status = self.calls.SerializedFMUstateSize(self.component, entry[0], ctypes.byref(size))
        if status >= ERROR:
            return status, None
        buf = ctypes.create_string_buffer(size.value)
        status = self.calls.SerializeFMUstate(self.component, entry[0], buf, size.value)
        if status < ERROR:
            self.blobs[op[2]] = (buf.raw, entry[1])
        return status, None

    def _deserialize(self, op, legal):
        source, corruption, slot = op[1], op[2], op[3]
        if corruption[0] == "foreign":
            data, snap = self.foreign.get(corruption[1], b""), Snapshot(None, None, None)
            must_refuse = True
        else:
            if source not in self.blobs:
                return None, None
            data, snap = self.blobs[source]
            data, must_refuse, snap = corrupt(data, corruption, snap)
        handle = ctypes.c_void_p()
        status = self.calls.DeSerializeFMUstate(self.component, data, len(data), ctypes.byref(handle))
        if status < ERROR:
            if must_refuse:
                self._pending_findings.append(("corrupted state accepted", f"{op} deserialised"))
            old = self.handles.pop(slot, None)
            if old is not None:
                self.calls.FreeFMUstate(self.component, ctypes.byref(old[0]))
            self.handles[slot] = (handle, snap)
        return status, None


def corrupt(data: bytes, corruption: list, snap: Snapshot) -> tuple[bytes, bool, Snapshot]:
    """The bytes after CORRUPTION, whether a valid FMU must refuse them, and what is known of them."""
    kind = corruption[0]
    if kind == "none":
        return data, False, snap
    if kind == "truncate":
        return data[:max(0, len(data) - corruption[1])], True, snap
    if kind == "extend":
        return data + bytes(corruption[1]), True, snap
    n = len(data) // 8
    values = list(memoryview(data).cast("d")) if n else []
    slot = corruption[1] % max(n, 1)
    if not values:
        return data, False, snap
    if kind == "nonfinite":
        values[slot] = corruption[2]
        must = True
    elif kind == "state":  # the state-machine field, edited to another valid value
        must = values[STATE_SLOT] != corruption[2]
        slot, values[STATE_SLOT] = STATE_SLOT, corruption[2]
    else:  # "value": a finite value anywhere; any change breaks the seal
        must = struct.pack("d", values[slot]) != struct.pack("d", corruption[2])
        values[slot] = corruption[2]
    return struct.pack(f"{len(values)}d", *values), must, Snapshot(None, None, None)


# ---- generating sequences ---------------------------------------------------------------------

def generate(fmu: LoadedFmu, seed: int, length: int = 40) -> list[list]:
    """A random call sequence: mostly a legal run, with illegal and extreme calls mixed in."""
    rng = random.Random(f"{fmu.name}:{seed}")
    ops: list[list] = [["instantiate"]]
    t, stop, phase = 0.0, None, INSTANTIATED

    def value(var: Variable) -> float:
        r = rng.random()
        lo = var.min if math.isfinite(var.min) else -1e3
        hi = var.max if math.isfinite(var.max) else 1e3
        if r < 0.55:
            return var.start
        if r < 0.75:
            return rng.uniform(lo, hi)
        if r < 0.85:
            return rng.choice([lo, hi, math.nextafter(lo, math.inf) if lo == 0 else lo * (1 + 1e-12)])
        if r < 0.92:
            return rng.choice(BAD_NUMBERS)
        return rng.choice([hi * 10 + 1, lo - 1 - abs(lo), 1e308, -1e308])

    def legal_next() -> list:
        """A call the standard allows in PHASE, mostly moving a normal run along."""
        nonlocal t, stop, phase
        if phase == INSTANTIATED:
            r = rng.random()
            if r < 0.3:
                stop = rng.choice([None, None, None, 10.0, 0.05])
                phase = "setup done"
                return ["setup", 0.0, stop]
            var = rng.choice(fmu.settable)
            return ["set", var.name, var.start if rng.random() < 0.6 else rng.uniform(
                var.min if math.isfinite(var.min) else -10, var.max if math.isfinite(var.max) else 10)]
        if phase == "setup done":
            phase = INIT
            return ["enter"]
        if phase == INIT:
            if rng.random() < 0.4:
                phase = EVENT if fmu.model_exchange else STEP_COMPLETE
                return ["exit"]
            var = rng.choice(fmu.settable)
            return ["set", var.name, value(var)]
        if phase in (EVENT, CT):
            return model_exchange_next()
        r = rng.random()
        if r < 0.5:
            h = rng.choice(LEGAL_STEPS) if rng.random() < 0.7 else rng.uniform(1e-6, 0.3)
            if stop is not None and t + h > stop:
                return ["get", [v.name for v in fmu.outputs]]
            op = ["step", t, h]
            t += h
            return op
        if r < 0.75:
            return ["get", [v.name for v in fmu.outputs]]
        if r < 0.9:
            inputs = [v for v in fmu.settable if v.causality == "input"] or fmu.settable
            var = rng.choice(inputs)
            return ["set", var.name, value(var)]
        return ["getstate", rng.randrange(3)] if rng.random() < 0.6 else ["serialize", rng.randrange(3),
                                                                         rng.randrange(3)]

    def model_exchange_next() -> list:
        """A legal Model Exchange call in event or continuous-time mode."""
        nonlocal t, phase
        r = rng.random()
        if phase == EVENT:
            if r < 0.3:
                return ["update"]
            if r < 0.65:
                phase = CT
                return ["enterct"]
            if r < 0.8:
                return ["get", [v.name for v in fmu.outputs]]
            return ["set", (var := rng.choice(inputs)).name, value(var)]
        if r < 0.25:
            t += rng.choice(LEGAL_STEPS) * rng.choice([1e-3, 0.1, 1.0])
            return ["settime", t]
        if r < 0.4:
            return ["getx", 0]
        if r < 0.55:
            return ["setx", rng.choice([0.0, 1e-9, 1e-6, -1e-6]), None, 0.0, 0]
        if r < 0.65:
            return ["getdx", 0]
        if r < 0.7:
            return ["getz", 0]
        if r < 0.75:
            return ["completed"]
        if r < 0.8:
            phase = EVENT
            return ["enterevent"]
        if r < 0.88:
            return ["get", [v.name for v in fmu.outputs]]
        if r < 0.94:
            return ["set", (var := rng.choice(inputs)).name, value(var)]
        return ["getstate", rng.randrange(3)] if rng.random() < 0.6 else ["serialize", rng.randrange(3),
                                                                         rng.randrange(3)]

    def model_exchange_deviation() -> list:
        """A Model Exchange call with a bad argument, or in any state (illegal in Co-Simulation)."""
        r = rng.random()
        if r < 0.25:
            return ["settime", rng.choice([math.nan, math.inf, -1.0, -1e-9, t, t + 1e3, 1e300])]
        if r < 0.5:
            return ["setx", rng.choice([0.0, 1e3, -2.0, 1e300]), rng.choice([None, rng.randrange(7)]),
                    rng.choice([*BAD_NUMBERS, 1e300, -1e300, 0.0]), rng.choice([0, 0, 0, -1, 1, -7])]
        if r < 0.75:
            return [rng.choice(["getx", "getdx", "getz"]), rng.choice([0, -1, 1, -100])]
        return [rng.choice(["enterct", "enterevent", "update", "completed"])]

    inputs = [v for v in fmu.settable if v.causality == "input"] or fmu.settable
    for _ in range(length):
        if rng.random() < 0.8:
            ops.append(legal_next())
            continue
        if rng.random() < (0.35 if fmu.model_exchange else 0.05):
            ops.append(model_exchange_deviation())
            if rng.random() < 0.3:
                ops.append(["reset"])
                t, stop, phase = 0.0, None, INSTANTIATED
            continue
        r = rng.random()
        if r < 0.05:
            ops.append(["reset"])
            t, stop, phase = 0.0, None, INSTANTIATED
        elif r < 0.08:
            ops += [["free"], ["instantiate"]]
            t, stop, phase = 0.0, None, INSTANTIATED
        elif r < 0.12:
            start = rng.choice([0.0, 1.5, -2.0, math.nan, 1e15])
            ops.append(["setup", start, rng.choice([None, start + 10.0, start - 1.0, math.inf])])
        elif r < 0.15:
            ops.append([rng.choice(["enter", "exit", "terminate"])])
        elif r < 0.35:
            var = rng.choice(fmu.variables)
            ops.append(["set", var.name if rng.random() < 0.95 else 999999, value(var)])
        elif r < 0.40:
            ops.append(["get", [v.name for v in fmu.outputs] + [999999]])
        elif r < 0.62:
            q = rng.random()
            h = rng.choice(EXTREME_STEPS) if q < 0.5 else rng.choice([0.0, -1e-3, math.nan, math.inf, 0.5])
            at = t if rng.random() < 0.6 else rng.choice([t + 1e-3, t - 0.5, t + 0.5, math.nan, t * (1 + 1e-13)])
            ops.append(["step", at, h])
        elif r < 0.70:
            ops.append(["status", rng.choice(["real", "boolean", "plain"])])
        elif r < 0.78:
            ops.append([rng.choice(["getstate", "setstate", "freestate"]), rng.randrange(3)])
        else:
            q = rng.random()
            if q < 0.2:
                corruption = ["none"]
            elif q < 0.32:
                corruption = ["truncate", rng.choice([1, 8, 16, 64])]
            elif q < 0.4:
                corruption = ["extend", rng.choice([8, 3])]
            elif q < 0.55:
                corruption = ["nonfinite", rng.randrange(64), rng.choice(BAD_NUMBERS)]
            elif q < 0.67:
                corruption = ["state", 0, float(rng.choice([1, 2, 4, 8, 16, 32, 64, 3, 1e9]))]
            elif q < 0.87:
                corruption = ["value", rng.randrange(64), rng.choice([0.0, -1.0, 1e300, -1e300, 1e-320, 7.0])]
            else:
                corruption = ["foreign", rng.choice(fmu.foreign_names or [n for n in FMU_NAMES if n != fmu.name])]
            ops.append(["deserialize", rng.randrange(3), corruption, rng.randrange(3)])
            if rng.random() < 0.7:
                ops.append(["setstate", ops[-1][3]])
        if rng.random() < 0.4:  # most deviations end in the error state: often start over
            ops.append(["reset"])
            t, stop, phase = 0.0, None, INSTANTIATED
    return ops


# ---- running sequences in children ------------------------------------------------------------

@dataclass
class Outcome:
    fmu: str
    seed: int | None
    ops: list
    calls: int
    findings: list = field(default_factory=list)  # (category, op index, detail)
    seconds: float = 0.0
    trace: str = ""  # a crashed child's fatal-error trace (faulthandler), kept off the test log


def _child_main(fmu: LoadedFmu, foreign: dict, ops: list, fd: int) -> None:
    out = os.fdopen(fd, "w", buffering=1)
    child = Child(fmu, foreign, None)
    for k, op in enumerate(ops):
        out.write(json.dumps(["call", k]) + "\n")
        try:
            found = child.run(op)
        except Exception as e:  # the harness's own failure: reported, never mistaken for the FMU's
            out.write(json.dumps(["harness", k, repr(e)]) + "\n")
            break
        for category, detail in found:
            out.write(json.dumps(["finding", k, category, detail]) + "\n")
    out.write(json.dumps(["done"]) + "\n")
    out.flush()


def _selftest(what: str, amount: float) -> None:
    """What the harness must classify: "crash" (SIGSEGV), "sleep" AMOUNT s (blocked, no CPU used),
    "spin" AMOUNT s of CPU time (math.inf: an unbounded loop), "pin" to CPU AMOUNT."""
    if what == "crash":
        os.kill(os.getpid(), signal.SIGSEGV)
    elif what == "sleep":
        time.sleep(amount)
    elif what == "spin":
        end = time.process_time() + amount
        while time.process_time() < end:
            pass
    elif what == "pin":
        os.sched_setaffinity(0, {int(amount)})


def run_sequence(fmu: LoadedFmu, ops: list, foreign: dict, timeout: float, seed: int | None = None,
                 backstop: float | None = None) -> Outcome:
    """Run OPS in a forked child with TIMEOUT seconds of CPU time (and BACKSTOP seconds of wall-clock
    time, BACKSTOP_FACTOR * TIMEOUT by default); classify crash and hang here, the rest in the child."""
    backstop = BACKSTOP_FACTOR * timeout if backstop is None else backstop
    read_fd, write_fd = os.pipe()
    # The child's fatal-error trace (faulthandler, which pytest enables) goes here, into the finding,
    # not onto the test log, where a crash made on purpose read like a real one.
    trace = tempfile.TemporaryFile()
    start = time.monotonic()
    pid = os.fork()
    if pid == 0:  # the child
        os.close(read_fd)
        code = 0
        try:
            if faulthandler.is_enabled():
                faulthandler.enable(file=trace)
            signal.signal(signal.SIGPROF, signal.SIG_DFL)  # its default action ends the process
            signal.setitimer(signal.ITIMER_PROF, timeout)  # counts this process's CPU time only
            _child_main(fmu, foreign, ops, write_fd)
        except BaseException:
            code = 3
        os._exit(code)
    os.close(write_fd)
    outcome = Outcome(fmu.name, seed, ops, 0)
    buffer, last_call, done, harness = b"", -1, False, None
    deadline = start + backstop
    with os.fdopen(read_fd, "rb") as pipe:
        while True:
            left = deadline - time.monotonic()
            if left <= 0:
                break
            ready, _, _ = select.select([pipe], [], [], left)
            if not ready:
                break
            chunk = os.read(pipe.fileno(), 1 << 16)
            if not chunk:
                break
            buffer += chunk
            *lines, buffer = buffer.split(b"\n")
            for line in lines:
                msg = json.loads(line)
                if msg[0] == "call":
                    last_call = msg[1]
                elif msg[0] == "finding":
                    outcome.findings.append((msg[2], msg[1], msg[3]))
                elif msg[0] == "harness":
                    harness = msg
                elif msg[0] == "done":
                    done = True
    at = ops[last_call] if last_call >= 0 else None
    if not done and time.monotonic() >= deadline:
        os.kill(pid, signal.SIGKILL)
        os.waitpid(pid, 0)
        outcome.findings.append(("hang", last_call, f"{at} made no progress within the {backstop} s "
                                                    "wall-clock backstop"))
    else:
        _, status = os.waitpid(pid, 0)
        if harness is not None:
            raise RuntimeError(f"fuzzer failure in {fmu.name} at call {harness[1]} {ops[harness[1]]}: {harness[2]}")
        if os.WIFSIGNALED(status) and os.WTERMSIG(status) == signal.SIGPROF:
            outcome.findings.append(("hang", last_call, f"{at} did not return within {timeout} s of CPU time"))
        elif not done or os.WIFSIGNALED(status) or os.WEXITSTATUS(status) != 0:
            how = (f"signal {signal.Signals(os.WTERMSIG(status)).name}" if os.WIFSIGNALED(status)
                   else f"exit {os.WEXITSTATUS(status)}")
            trace.seek(0)
            captured = trace.read().decode(errors="replace").strip()
            first = next((line for line in captured.splitlines() if line.startswith("Fatal Python error")), "")
            outcome.findings.append(("crash", last_call, f"{at}: {how}" + (f" ({first})" if first else "")))
            outcome.trace = captured
    trace.close()
    outcome.calls = last_call + 1
    outcome.seconds = time.monotonic() - start
    return outcome


def sample_state(fmu: LoadedFmu) -> bytes:
    """An initialised, stepped state of FMU, serialised (run in a child: the parent never instantiates)."""
    read_fd, write_fd = os.pipe()
    pid = os.fork()
    if pid == 0:
        os.close(read_fd)
        try:
            child = Child(fmu, {}, None)
            child.instantiate()
            run = ["enterct"] if fmu.model_exchange else ["step", 0.0, 1e-3]
            for op in (["setup", 0.0, None], ["enter"], ["exit"], run, ["getstate", 0], ["serialize", 0, 0]):
                child.run(op)
            os.write(write_fd, child.blobs[0][0])
        finally:
            os._exit(0)
    os.close(write_fd)
    with os.fdopen(read_fd, "rb") as pipe:
        data = pipe.read()
    os.waitpid(pid, 0)
    return data


@dataclass
class Campaign:
    fmus: dict[str, LoadedFmu]
    foreign: dict[str, bytes]

    @classmethod
    def load(cls, paths, workdir) -> "Campaign":
        """PATHS: FMU files, or (file, True) to fuzz the FMU's Model Exchange interface."""
        entries = [p if isinstance(p, tuple) else (p, False) for p in paths]
        loaded = [LoadedFmu(Path(p), Path(workdir), me) for p, me in entries]
        fmus = {f.name: f for f in loaded}
        for f in loaded:
            f.foreign_names = [n for n in fmus if n != f.name]
        return cls(fmus, {name: sample_state(f) for name, f in fmus.items()})

    def run(self, name: str, seeds, timeout: float = 3.0, length: int = 40) -> list[Outcome]:
        fmu = self.fmus[name]
        return [run_sequence(fmu, generate(fmu, s, length), self.foreign, timeout, s) for s in seeds]

    def replay(self, name: str, ops: list, timeout: float = 3.0, backstop: float | None = None) -> Outcome:
        return run_sequence(self.fmus[name], ops, self.foreign, timeout, backstop=backstop)

    def minimise(self, name: str, ops: list, category: str, timeout: float = 3.0) -> list:
        """The shortest call list (removing one call at a time) that still shows CATEGORY."""
        def shows(candidate):
            return any(f[0] == category for f in self.replay(name, candidate, timeout).findings)
        # Up to the first call that showed it, then drop calls while it still shows.
        first = min(f[1] for f in self.replay(name, ops, timeout).findings if f[0] == category)
        current = ops[:first + 1]
        k = 0
        while k < len(current):
            candidate = current[:k] + current[k + 1:]
            if candidate and shows(candidate):
                current = candidate
            else:
                k += 1
        return current


def summarise(outcomes: list[Outcome]) -> dict:
    counts = Counter()
    sequences_with = Counter()
    for o in outcomes:
        cats = {f[0] for f in o.findings}
        for f in o.findings:
            counts[f[0]] += 1
        for c in cats:
            sequences_with[c] += 1
    return {"sequences": len(outcomes), "calls": sum(o.calls for o in outcomes),
            "findings": {c: counts[c] for c in CATEGORIES},
            "sequences_with": {c: sequences_with[c] for c in CATEGORIES}}
