"""The engines of `hdjoint estimate`, fed a recording a block at a time so
that memory does not grow with its length: JointTorqueEstimator.fmu, or the
C++ core's EstimatorStream (the batch engine), which carries the estimator
across blocks and gives the same numbers as a run on the whole recording."""
from __future__ import annotations

import sys

import numpy as np

from hdjoint.io.outputs import printable

INPUTS = ("i_m", "theta_m", "theta_l")
SHOWN_WARNINGS = 5


def warn_fmu_messages(path, messages) -> None:
    """The FMU's fmi2Warning messages (e.g. an outlier sample the joint-state filter predicted over)."""
    for message in messages[:SHOWN_WARNINGS]:
        print(f"warning: {printable(path)}: {message}", file=sys.stderr)
    if len(messages) > SHOWN_WARNINGS:
        print(f"warning: {printable(path)}: {len(messages) - SHOWN_WARNINGS} more warnings", file=sys.stderr)


class RejectedSamples:
    """The rows whose step the filters predicted over (the batch status column): outliers the joint-state
    filter rejected, gaps (a step that held its inputs over several samples) and readings no sensor could
    produce (gated: treated as missing), to say where."""

    def __init__(self, path):
        self.path = path
        self.count, self.first = {"rejected": 0, "held": 0, "gated": 0}, {"rejected": [], "held": [], "gated": []}

    def add(self, time, status) -> None:
        from hdjoint import _core
        status = np.asarray(status)
        for kind, code in (("rejected", _core.STATUS_SAMPLE_REJECTED), ("held", _core.STATUS_READINGS_HELD),
                           ("gated", _core.STATUS_READING_GATED)):
            rows = np.flatnonzero(status == code)
            self.count[kind] += rows.size
            self.first[kind] += [float(time[j]) for j in rows[:SHOWN_WARNINGS - len(self.first[kind])]]

    def _where(self, kind) -> str:
        more = ", ..." if self.count[kind] > len(self.first[kind]) else ""
        return f"{', '.join(f'{t:g} s' for t in self.first[kind])}{more}"

    def warn(self) -> None:
        from hdjoint import _core
        if self.count["rejected"]:
            print(f"warning: {printable(self.path)}: the joint-state filter rejected {self.count['rejected']} "
                  "outlier sample(s) "
                  f"and predicted over them (at {self._where('rejected')}); tau_hat_std grows there", file=sys.stderr)
        if self.count["gated"]:
            print(f"warning: {self.path}: {self.count['gated']} row(s) hold a reading no sensor could produce (a "
                  f"current beyond {_core.WILD_CURRENT_MULTIPLE:g} x i_peak, a non-finite value or an encoder jump "
                  f"faster than omega_m_max, at {self._where('gated')}): treated as missing, the filters predicted "
                  "over them; tau_ukf_std and tau_hat_std grow there", file=sys.stderr)
        if self.count["held"]:
            print(f"warning: {printable(self.path)}: {self.count['held']} row(s) step over more than one sample "
                  "(a gap, at "
                  f"{self._where('held')}): the filters predicted over the samples without a reading; "
                  "tau_ukf_std and tau_hat_std grow there", file=sys.stderr)


class FmuEngine:
    """JointTorqueEstimator.fmu over a segment's rows (a new instance for each segment)."""

    def __init__(self, params: dict, ts: float, path):
        from hdjoint.fmu.runner import ESTIMATOR_OUTPUTS
        self.params, self.ts, self.path, self.outputs = params, ts, path, ESTIMATOR_OUTPUTS
        self._instance = self._stepper = None

    def run(self, time, inputs, end: float, last: bool) -> dict:
        """Row j steps to row j+1's time, the last one to END (by Ts exactly when it is the segment's LAST)."""
        from hdjoint.fmu.runner import FmuInstance
        from hdjoint.fmu.shipped import fmu_path
        if self._instance is None:
            self._instance = FmuInstance(fmu_path("JointTorqueEstimator"), "estimator")
            self._instance.start(float(time[0]), None, self.params, dict(zip(INPUTS, map(float, inputs[0]))))
            self._stepper = self._instance.stepper(INPUTS, self.outputs)
        steps = np.diff(np.append(time, end))
        if last:
            steps[-1] = self.ts
        result = np.empty((len(time), len(self.outputs)))
        rows, times = inputs.tolist(), time.tolist()
        for j, h in enumerate(steps.tolist()):
            result[j] = self._stepper.step(times[j], h, rows[j])
        return {name: result[:, k] for k, name in enumerate(self.outputs)}

    def end_segment(self) -> None:
        if self._instance is not None:
            warn_fmu_messages(self.path, [m for status, m in self._instance.messages if status == "WARNING"])
            self._instance.close()
            self._instance = None


class CoreEngine:
    """The C++ core's EstimatorStream over a segment's rows; with keep_records, also the joint-state
    filter's samples for the smoother (last_record per row, records per block)."""

    def __init__(self, params: dict, path, keep_records: bool = False):
        self.params, self.keep_records = params, keep_records
        self.rejected = RejectedSamples(path)
        self._stream = None

    def run(self, time, inputs, end: float, last: bool) -> dict:
        from hdjoint import _core
        if self._stream is None:
            self._stream = _core.EstimatorStream(self.params, float(time[0]), self.keep_records)
        columns = [np.ascontiguousarray(inputs[:, k]) for k in range(len(INPUTS))]
        out = self._stream.run(np.ascontiguousarray(time), *columns, end)
        self.rejected.add(time, out["status"])
        return out

    def end_segment(self) -> None:
        self._stream = None


class BothEngines:
    """The FMU's causal outputs with the core's filter records (--smooth with the FMU engine: the smoother
    runs over the core's joint-state filter, the same code)."""

    def __init__(self, fmu: FmuEngine, core: CoreEngine):
        self.fmu, self.core = fmu, core

    def run(self, time, inputs, end: float, last: bool) -> dict:
        core = self.core.run(time, inputs, end, last)
        return {**self.fmu.run(time, inputs, end, last), "last_record": core["last_record"],
                "records": core["records"]}

    def end_segment(self) -> None:
        self.fmu.end_segment()
        self.core.end_segment()


class RowFeeder:
    """Gives ENGINE a segment's rows a block at a time and EMIT(time, outputs) what it computed, in order.
    Row j is a communication point stepped to row j+1's time, so a block's last row waits for the next
    block; a segment's last row steps by Ts (as a recording's last row does)."""

    def __init__(self, engine, ts: float, emit):
        self.engine, self.ts, self.emit = engine, ts, emit
        self._pending = None  # (time, inputs) of the row awaiting its step, as 1-row arrays

    def feed(self, time, inputs) -> None:
        if len(time) == 0:
            return
        if self._pending is not None:
            time = np.concatenate((self._pending[0], time))
            inputs = np.vstack((self._pending[1], inputs))
        if len(time) > 1:
            self.emit(time[:-1], self.engine.run(time[:-1], inputs[:-1], float(time[-1]), False))
        self._pending = (time[-1:], inputs[-1:])

    def end_segment(self) -> None:
        if self._pending is not None:
            time, inputs = self._pending
            self._pending = None
            self.emit(time, self.engine.run(time, inputs, float(time[0]) + self.ts, True))
        self.engine.end_segment()
