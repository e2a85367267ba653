"""`hdjoint estimate` from file to file: the recording is read block by block
and its time base checked as it comes (unit, Ts, gaps, jitter); the FMU
engine streams, so memory stays flat whatever the recording's length. The
batch engine and the smoother need the whole recording at once."""
from __future__ import annotations

import sys
from dataclasses import dataclass, field

import numpy as np

from .jobs import UserError, check_output_file, read_params
from .metrics import RunningErrorFigures
from .recording import CHUNK_ROWS, CsvWriter, Recording, RecordingError, iter_recording
from .timebase import TIME_UNITS, TimeBaseError, check_step, describe, given_ts, irregular_steps, sample_period

FIGURES_OF = ("tau_compliance", "tau_ukf", "tau_hat")
SHOWN_WARNINGS = 5


def warn_fmu_messages(path, messages) -> None:
    """The FMU's fmi2Warning messages (e.g. an outlier sample the joint-state filter predicted over)."""
    for message in messages[:SHOWN_WARNINGS]:
        print(f"warning: {path}: {message}", file=sys.stderr)
    if len(messages) > SHOWN_WARNINGS:
        print(f"warning: {path}: {len(messages) - SHOWN_WARNINGS} more warnings", file=sys.stderr)


def warn_rejected_samples(path, time, status) -> None:
    """The joint-state filter predicted over outlier samples (the batch status column): say where."""
    from . import _core
    rejected = np.flatnonzero(np.asarray(status) == _core.STATUS_SAMPLE_REJECTED)
    if rejected.size:
        first = ", ".join(f"{time[j]:g} s" for j in rejected[:SHOWN_WARNINGS])
        more = ", ..." if rejected.size > SHOWN_WARNINGS else ""
        print(f"warning: {path}: the joint-state filter rejected {rejected.size} outlier sample(s) and predicted "
              f"over them (at {first}{more}); tau_hat_std grows there", file=sys.stderr)


@dataclass
class Options:
    recording: str
    output: str
    params: str | None = None
    engine: str = "fmu"
    smooth: bool = False
    time_unit: str | None = None
    split_gaps: bool = False
    allow_jitter: bool = False


@dataclass
class Block:
    """Consecutive samples (time in seconds) and the rows at which a new segment starts (a split gap)."""
    rec: Recording
    cuts: list[int] = field(default_factory=list)


class TimedBlocks:
    """The recording's blocks with the time-base policy applied: the first
    block fixes the median step (and Ts when the parameters leave it open);
    every gap and jitter is refused with its line, or a gap splits the
    recording when asked (with a warning naming it)."""

    def __init__(self, opts: Options, ts_given: float | None):
        self.opts = opts
        self._blocks = self._read()
        self._first = next(self._blocks)
        while len(self._first.recording) < 2:  # only a file this short: read on, for its error
            self._first = next(self._blocks)
        self.step = float(np.median(np.diff(self._first.recording.time)))
        self.ts = sample_period(self.step, ts_given)
        self._guard(check_step, opts.recording, self.step, opts.time_unit, self.ts)
        self.gaps: list[str] = []

    def _guard(self, fn, *args):
        try:
            return fn(*args)
        except (RecordingError, TimeBaseError) as e:
            raise UserError(str(e)) from None

    def _read(self):
        factor = TIME_UNITS[self.opts.time_unit or "s"]
        chunks = iter_recording(self.opts.recording)
        while True:
            chunk = self._guard(next, chunks, None)
            if chunk is None:
                return
            chunk.recording.time = chunk.recording.time * factor
            yield chunk

    def __iter__(self):
        previous = None  # (time, line) of the row before the block
        for chunk in self._chain():
            rec, cuts = chunk.recording, []
            for bad in irregular_steps(rec.time, self.step, None if previous is None else previous[0]):
                before = int(chunk.lines[bad.index]) if bad.index >= 0 else previous[1]
                text = describe(bad, before, int(chunk.lines[bad.index + 1]), self.step)
                if bad.kind == "gap" and self.opts.split_gaps:
                    print(f"warning: {self.opts.recording}: {text}: the estimator restarts after it",
                          file=sys.stderr)
                    self.gaps.append(text)
                    cuts.append(bad.index + 1)
                elif bad.kind == "jitter" and self.opts.allow_jitter:
                    continue
                else:
                    hint = "--split-gaps" if bad.kind == "gap" else "--allow-jitter"
                    raise UserError(f"{self.opts.recording}: {text}; the estimator assumes a fixed sample period "
                                    f"(pass {hint} to accept it, see docs/robustness.md)")
            previous = (float(rec.time[-1]), int(chunk.lines[-1]))
            yield Block(rec, cuts)

    def _chain(self):
        yield self._first
        yield from self._blocks


def _pieces(n: int, cuts: list[int]):
    """(start, stop, starts_a_segment) of a block of N rows cut at CUTS."""
    bounds = [0, *cuts, n]
    for k in range(len(bounds) - 1):
        if bounds[k] < bounds[k + 1] or k > 0:
            yield bounds[k], bounds[k + 1], k > 0


class _StreamedFmu:
    """JointTorqueEstimator.fmu fed a segment at a time. Each row is a
    communication point stepped to the next row's time, so a block's last row
    waits for the next block; a segment's last row steps by Ts (as
    run_estimator_fmu does with a recording's last row)."""

    def __init__(self, params: dict, ts: float, emit, path):
        from .fmu_runner import ESTIMATOR_OUTPUTS
        self.params, self.ts, self.emit, self.path = params, ts, emit, path
        self.outputs = ESTIMATOR_OUTPUTS
        self._instance = self._stepper = None
        self._pending = None  # (time, inputs) of the row awaiting its step

    def feed(self, time: np.ndarray, inputs: np.ndarray) -> None:
        from .fmu_runner import FmuInstance
        from .fmus import fmu_path
        if self._instance is None:
            self._instance = FmuInstance(fmu_path("JointTorqueEstimator"), "estimator")
            self._instance.start(float(time[0]), None, self.params, dict(zip(("i_m", "theta_m", "theta_l"),
                                                                              map(float, inputs[0]))))
            self._stepper = self._instance.stepper(("i_m", "theta_m", "theta_l"), self.outputs)
        if self._pending is not None:
            time = np.concatenate(([self._pending[0]], time))
            inputs = np.vstack([self._pending[1], inputs])
        steps = np.diff(time)
        result = np.empty((len(steps), len(self.outputs)))
        rows = inputs.tolist()
        for j, h in enumerate(steps.tolist()):
            result[j] = self._stepper.step(float(time[j]), h, rows[j])
        self._pending = (float(time[-1]), inputs[-1])
        if len(steps):
            self.emit(time[:-1], result)

    def end_segment(self) -> None:
        if self._pending is not None:
            t, row = self._pending
            self.emit(np.array([t]), np.array([self._stepper.step(t, self.ts, row.tolist())]))
            self._pending = None
        self.close()

    def close(self) -> None:
        if self._instance is not None:
            warn_fmu_messages(self.path, [m for status, m in self._instance.messages if status == "WARNING"])
            self._instance.close()
            self._instance = None


def estimate_to_file(opts: Options) -> dict:
    """Run the estimator over OPTS.recording into OPTS.output; returns
    {estimate name: ErrorFigures against tau_sensor} (empty without a sensor)."""
    from . import parameters
    check_output_file(opts.output, inputs=(opts.recording, opts.params))  # before any work
    params = read_params(opts.params)
    blocks = TimedBlocks(opts, given_ts(opts.params))
    ts_from_recording = given_ts(opts.params) is None
    if ts_from_recording:
        params["Ts"] = blocks.ts
    params = parameters.for_estimator(params)
    try:
        run = _streamed if opts.engine == "fmu" and not opts.smooth else _whole
        figures = run(opts, blocks, params)
    except RuntimeError as e:  # FmuError, or the batch path's invalid input
        raise UserError(f"{opts.recording}: {e}") from None
    if ts_from_recording and abs(blocks.ts - 1e-3) > 1e-9:
        print(f"note: estimator sample period Ts = {blocks.ts:g} s (the recording's median step)", file=sys.stderr)
    return figures


def _streamed(opts: Options, blocks: TimedBlocks, params: dict) -> dict:
    from .fmu_runner import ESTIMATOR_OUTPUTS
    figures = {name: RunningErrorFigures() for name in FIGURES_OF}
    with CsvWriter(opts.output, ("time", *ESTIMATOR_OUTPUTS)) as out:
        sensor_rows: list = []

        def emit(time, result):
            columns = {"time": time, **{name: result[:, k] for k, name in enumerate(ESTIMATOR_OUTPUTS)}}
            out.write(columns)
            if sensor_rows:
                sensor, sensor_rows[:] = np.concatenate(sensor_rows), []
                for name in FIGURES_OF:
                    figures[name].add(columns[name], sensor[:len(time)])
                if len(sensor) > len(time):
                    sensor_rows.append(sensor[len(time):])

        fmu = _StreamedFmu(params, blocks.ts, emit, opts.recording)
        has_sensor = None
        try:
            for block in blocks:
                rec = block.rec
                has_sensor = rec.tau_sensor is not None if has_sensor is None else has_sensor
                inputs = np.column_stack([rec.i_m, rec.theta_m, rec.theta_l])
                for start, stop, new_segment in _pieces(len(rec), block.cuts):
                    if new_segment:
                        fmu.end_segment()
                    if has_sensor:
                        sensor_rows.append(rec.tau_sensor[start:stop])
                    fmu.feed(rec.time[start:stop], inputs[start:stop])
            fmu.end_segment()
        finally:
            fmu.close()  # also when a later block is refused
    return {name: f.result() for name, f in figures.items()} if has_sensor else {}


def _whole(opts: Options, blocks: TimedBlocks, params: dict) -> dict:
    from . import _core
    from .fmu_runner import ESTIMATOR_OUTPUTS, run_estimator_fmu
    from .metrics import error_figures
    parts, segments = [], [[]]
    for block in blocks:
        for start, stop, new_segment in _pieces(len(block.rec), block.cuts):
            if new_segment:
                segments.append([])
            segments[-1].append(block.rec.slice(start, stop))
    names = list(ESTIMATOR_OUTPUTS) + (["tau_smooth", "tau_smooth_std"] if opts.smooth else [])
    for pieces in segments:
        r = {name: np.concatenate([getattr(p, name) for p in pieces])
             for name in ("time", "i_m", "theta_m", "theta_l")}
        args = (r["time"], r["i_m"], r["theta_m"], r["theta_l"])
        if opts.engine == "fmu":
            warnings: list[str] = []
            est = run_estimator_fmu(*args, params, warnings=warnings)
            warn_fmu_messages(opts.recording, warnings)
        else:
            est = _core.run_estimator(params, *args)
            warn_rejected_samples(opts.recording, r["time"], est["status"])
        if opts.smooth:
            # The smoother runs offline over the joint-state filter's samples, in
            # the batch path, whichever engine computed the causal estimates.
            smoothed = _core.run_estimator(params, *args, smooth=True)
            est["tau_smooth"], est["tau_smooth_std"] = smoothed["tau_smooth"], smoothed["tau_smooth_std"]
        parts.append({"time": r["time"], **{name: est[name] for name in names}})
    columns = {name: np.concatenate([p[name] for p in parts]) for name in ["time", *names]}
    with CsvWriter(opts.output, list(columns)) as out:
        for start in range(0, len(columns["time"]), CHUNK_ROWS):  # formatted text a block at a time
            out.write({name: values[start:start + CHUNK_ROWS] for name, values in columns.items()})
    sensors = [p.tau_sensor for pieces in segments for p in pieces]
    if any(s is None for s in sensors):
        return {}
    sensor = np.concatenate(sensors)
    return {name: error_figures(columns[name], sensor) for name in FIGURES_OF + (("tau_smooth",) if opts.smooth else ())}
