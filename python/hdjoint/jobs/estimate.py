"""`hdjoint estimate` from file to file: the recording is read block by block
and its time base checked as it comes (unit, Ts, gaps, jitter); either engine
streams (estimate_engines), and the smoother keeps what its backward pass
needs on disk (estimate_smoother), so memory does not grow with the
recording's length. The filter's reading-time jitter (jsf_r_time), unless
the parameter file sets it, is measured on the first block, which the job
holds anyway: the filter needs it before its first sample, and a logger's
jitter does not change along a recording, so a second pass over the file
would buy nothing."""
from __future__ import annotations

import contextlib
import sys
from dataclasses import dataclass, field

import numpy as np

from hdjoint.estimation.engines import BothEngines, CoreEngine, FmuEngine, RowFeeder
from hdjoint.estimation.smoother import SMOOTH_COLUMNS, SmoothedRows
from hdjoint.jobs.inputs import UserError, check_output_file, locked_output, read_params
from hdjoint.estimation.metrics import RunningErrorFigures
from hdjoint.io.reading_jitter import ReadingJitter, reading_jitter
from hdjoint.io.outputs import printable
from hdjoint.io.screening import Degenerate, check_no_wrap, find_outliers
from hdjoint.io.recording import CHUNK_ROWS, CsvWriter, Recording, RecordingError, iter_recording
from hdjoint.io.timebase import (TIME_UNITS, TimeBaseError, check_step, describe, given_ts, irregular_steps,
    sample_period)

FIGURES_OF = ("tau_compliance", "tau_ukf", "tau_hat")
# The filter's parameter for when the encoders were read: measured on the recording unless the file sets it.
READING_JITTER = "jsf_r_time"


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
    current_sign: float = 1.0  # -1: the current is logged against the encoders' sense
    block_rows: int = CHUNK_ROWS  # rows read, estimated and written at a time


@dataclass
class Block:
    """Consecutive samples (time in seconds) and the rows at which a new segment starts (a split gap)."""
    rec: Recording
    cuts: list[int] = field(default_factory=list)


@dataclass(frozen=True)
class Estimated:
    figures: dict            # {estimate name: ErrorFigures against tau_sensor}, empty without a sensor
    jitter: ReadingJitter    # the reading-time jitter the filter ran with, and where it came from


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
        self._angles = None  # the last row's angles, for a wrap across blocks
        self.wild: list[tuple[str, int, float]] = []  # (column, line, value) of wild samples (io.screening)

    def _guard(self, fn, *args):
        try:
            return fn(*args)
        except (RecordingError, TimeBaseError, Degenerate) as e:
            raise UserError(str(e)) from None

    def _read(self):
        factor = TIME_UNITS[self.opts.time_unit or "s"]
        chunks = iter_recording(self.opts.recording, self.opts.block_rows)
        while True:
            chunk = self._guard(next, chunks, None)
            if chunk is None:
                return
            chunk.recording.time = chunk.recording.time * factor
            chunk.recording.i_m = chunk.recording.i_m * self.opts.current_sign
            yield chunk

    @property
    def first(self) -> Recording:
        return self._first.recording

    def __iter__(self):
        previous = None  # (time, line) of the row before the block
        for chunk in self._chain():
            rec, cuts = chunk.recording, []
            for bad in irregular_steps(rec.time, self.step, None if previous is None else previous[0]):
                before = int(chunk.lines[bad.index]) if bad.index >= 0 else previous[1]
                text = describe(bad, before, int(chunk.lines[bad.index + 1]), self.step)
                if bad.kind == "gap" and self.opts.split_gaps:
                    print(f"warning: {printable(self.opts.recording)}: {text}: the estimator restarts after it",
                          file=sys.stderr)
                    self.gaps.append(text)
                    cuts.append(bad.index + 1)
                elif bad.kind == "jitter" and self.opts.allow_jitter:
                    continue
                else:
                    hint = "--split-gaps" if bad.kind == "gap" else "--allow-jitter"
                    raise UserError(f"{self.opts.recording}: {text}; the estimator assumes a fixed sample period "
                                    f"(pass {hint} to accept it, see docs/robustness.md)")
            self._guard(check_no_wrap, rec, chunk.lines, self._angles)
            for name in ("i_m", "theta_m", "theta_l"):
                x = getattr(rec, name)
                self.wild += [(name, int(chunk.lines[k]), float(x[k])) for k in find_outliers(x, rec.time)]
            self._angles = {"theta_m": float(rec.theta_m[-1]), "theta_l": float(rec.theta_l[-1])}
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


def estimate_to_file(opts: Options) -> Estimated:
    """Run the estimator over OPTS.recording into OPTS.output; returns its
    error figures and the reading-time jitter it ran with."""
    check_output_file(opts.output, inputs=(opts.recording, opts.params))  # before any work
    with locked_output(opts.output):
        return _estimate_locked(opts)


def _estimate_locked(opts: Options) -> Estimated:
    from hdjoint.io import parameters
    params = read_params(opts.params)
    blocks = TimedBlocks(opts, given_ts(opts.params))
    jitter = _reading_jitter(opts.params, blocks.first, params)
    ts_from_recording = given_ts(opts.params) is None
    if ts_from_recording:
        params["Ts"] = blocks.ts
    params = parameters.for_estimator(params)
    try:
        figures = _estimate(opts, blocks, params)
    except RuntimeError as e:  # FmuError, or the batch path's invalid input
        raise UserError(f"{opts.recording}: {e}") from None
    if blocks.wild:
        shown = ", ".join(f"line {line} {name} = {value:.4g}" for name, line, value in blocks.wild[:5])
        more = f" and {len(blocks.wild) - 5} more" if len(blocks.wild) > 5 else ""
        print(f"warning: {printable(opts.recording)}: {len(blocks.wild)} "
              f"wild sample{'s' if len(blocks.wild) > 1 else ''} "
              f"({shown}{more}): the estimates around them are unreliable (hdjoint diagnose leaves such samples "
              "out)", file=sys.stderr)
    if ts_from_recording and abs(blocks.ts - 1e-3) > 1e-9:
        print(f"note: estimator sample period Ts = {blocks.ts:g} s (the recording's median step)", file=sys.stderr)
    return Estimated(figures, jitter)


def as_written(params: dict, params_path) -> dict:
    """PARAMS as hdjoint writes a set: READING_JITTER left out unless the user's file PARAMS_PATH sets it,
    so each recording estimated with the set has its own measured (an FMU takes 0, the default, alike)."""
    from hdjoint.io import parameters
    if READING_JITTER in parameters.stated(params_path):
        return params
    return {name: value for name, value in params.items() if name != READING_JITTER}


def _reading_jitter(params_path, first: Recording, params: dict) -> ReadingJitter:
    """The filter's READING_JITTER, set into PARAMS: the parameter file's, else measured on FIRST (both encoders)."""
    from hdjoint.io import parameters
    if READING_JITTER in parameters.stated(params_path):
        given = params[READING_JITTER]
        return ReadingJitter(given, given, given, f"as the parameter file sets it ({READING_JITTER})")
    found = measured_reading_jitter(first.time, first.theta_m, first.theta_l)
    params[READING_JITTER] = found.std
    return found


def measured_reading_jitter(time, theta_m, theta_l) -> ReadingJitter:
    """The reading-time jitter of both encoders' readings, with its interval at the diagnosis's coverage."""
    from hdjoint.diagnosis import INTERVAL
    return reading_jitter(time, (theta_m, theta_l), INTERVAL)


def _engine(opts: Options, params: dict, ts: float):
    if opts.engine == "fmu":
        fmu = FmuEngine(params, ts, opts.recording)
        return BothEngines(fmu, CoreEngine(params, opts.recording, keep_records=True)) if opts.smooth else fmu
    return CoreEngine(params, opts.recording, keep_records=opts.smooth)


def _estimate(opts: Options, blocks: TimedBlocks, params: dict) -> dict:
    """Every row through the engine, block by block; the rows written as they come, or, with the smoother,
    after its backward pass."""
    from hdjoint.fmu.runner import ESTIMATOR_OUTPUTS
    names = FIGURES_OF + (("tau_smooth",) if opts.smooth else ())
    figures = {name: RunningErrorFigures() for name in names}
    columns = ("time", *ESTIMATOR_OUTPUTS) + (SMOOTH_COLUMNS if opts.smooth else ())
    sensor_rows: list = []  # the sensor's values of the rows read but not yet emitted
    engine = _engine(opts, params, blocks.ts)
    with CsvWriter(opts.output, columns) as out, contextlib.ExitStack() as stack:
        smoothed = stack.enter_context(SmoothedRows(params, ESTIMATOR_OUTPUTS)) if opts.smooth else None

        def emit(time, result):
            sensor = _take(sensor_rows, len(time))
            if smoothed is not None:
                smoothed.add(time, result, sensor)
                return
            out.write({"time": time, **{name: result[name] for name in ESTIMATOR_OUTPUTS}})
            if sensor is not None:
                for name in FIGURES_OF:
                    figures[name].add(result[name], sensor)

        feeder = RowFeeder(engine, blocks.ts, emit)
        has_sensor = None
        try:
            for block in blocks:
                rec = block.rec
                has_sensor = rec.tau_sensor is not None if has_sensor is None else has_sensor
                inputs = np.column_stack([rec.i_m, rec.theta_m, rec.theta_l])
                for start, stop, new_segment in _pieces(len(rec), block.cuts):
                    if new_segment:
                        _end_segment(feeder, smoothed)
                    if has_sensor:
                        sensor_rows.append(rec.tau_sensor[start:stop])
                    feeder.feed(rec.time[start:stop], inputs[start:stop])
            _end_segment(feeder, smoothed)
        finally:
            engine.end_segment()  # also when a later block is refused
        if smoothed is not None:
            for time, result, sensor in smoothed.rows(opts.block_rows):
                out.write({"time": time, **result})
                if has_sensor:
                    for name in names:
                        figures[name].add(result[name], sensor)
    if opts.engine == "batch":
        engine.rejected.warn()
    return {name: f.result() for name, f in figures.items()} if has_sensor else {}


def _end_segment(feeder: RowFeeder, smoothed) -> None:
    feeder.end_segment()
    if smoothed is not None:
        smoothed.end_segment()


def _take(queue: list, n: int):
    """The first N values of the arrays queued in QUEUE (removed), or None when nothing is queued."""
    if not queue:
        return None
    values = np.concatenate(queue)
    queue[:] = [values[n:]] if len(values) > n else []
    return values[:n]
