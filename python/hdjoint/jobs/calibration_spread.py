"""The torque deviation a calibration leaves, for the estimates' deviations.

A filter's deviation (tau_hat_std, tau_smooth_std) is the state's, given
its parameter set; a calibrated set is itself uncertain, and without a
torque sensor its errors move the torque far more than the readings' noise
does. Its posterior (each calibrated parameter's interval and their
correlations, as the diagnosis gives them) is propagated to first order
along its principal axes: the set is moved one deviation along each axis
either way, the estimates are run again on the same recording, and half the
difference is that axis's deviation of each estimate, sample by sample; the
axes are independent, so their variances add. The joint's torque scale,
which the recordings do not inform, is one more axis: every torque-carrying
parameter at once, to either end of the scale's interval."""
from __future__ import annotations

import csv
import os
from dataclasses import dataclass

import numpy as np

from hdjoint.diagnosis import HELD_WITHOUT_SENSOR as HELD, ENCODER_ZERO, INTERVAL_Z
from hdjoint.estimation.engines import INPUTS, CoreEngine, RowFeeder
from hdjoint.io import parameters
from hdjoint.io.recording import CHUNK_ROWS, Recording
from hdjoint.jobs.joint_scale import scaled, torque_power

# The estimates with a deviation, as `hdjoint estimate` writes them (name, its deviation).
DEVIATIONS = {"tau_ukf": "tau_ukf_std", "tau_hat": "tau_hat_std", "tau_smooth": "tau_smooth_std"}
PARAMETERS, SCALE = "calibrated parameters", "joint torque scale"  # the two shares


@dataclass(frozen=True)
class CalibrationSpread:
    variance: dict[str, np.ndarray]  # per deviation column: the calibration's variance at each row, N.m^2
    shares: dict[str, float]         # PARAMETERS' and SCALE's RMS deviation of tau_hat, N.m


def principal_axes(calibration: dict, correlation: dict) -> tuple[list[str], np.ndarray]:
    """The calibrated parameters with a spread and the columns of one deviation along each axis of their
    posterior (its marginal over them), in their own units. Not the held one (the scale is its own axis),
    nor the encoder zero (placed anew on each recording, with each set)."""
    names = [n for n, e in calibration.items()
             if n not in (HELD, ENCODER_ZERO) and e.get("lo") is not None and e["lo"] < e["hi"]]
    sd = np.array([(calibration[n]["hi"] - calibration[n]["lo"]) / (2.0 * INTERVAL_Z) for n in names])
    r = np.eye(len(names))
    for i, n in enumerate(names):
        for j, m in enumerate(names):
            if i != j:
                r[i, j] = correlation.get(n, {}).get(m, 0.0)
    cov = (r + r.T) / 2.0 * np.outer(sd, sd)
    values, vectors = np.linalg.eigh(cov)
    keep = values > 1e-12 * max(values.max(initial=0.0), 1e-300)
    return names, vectors[:, keep] * np.sqrt(values[keep])


def _sets(run_params: dict, calibration: dict, correlation: dict, estimates: dict, scale: float,
          interval: tuple[float, float] | None):
    """(share, the two sets either way) along each axis: RUN_PARAMS moved, as it is used (scaled); the
    encoder zero is placed on the recording for each set by the caller."""
    names, axes = principal_axes(calibration, correlation)
    table = parameters.table()

    def moved(step: np.ndarray) -> dict:
        # Within each range (its limit is no spread), then scaled as calibrate-from scales the set.
        at = {n: min(max(estimates[n] + d, table[n].min), table[n].max) for n, d in zip(names, step)}
        return {**run_params, **{n: v for n, v in scaled({**estimates, **at}, scale).items() if n in at}}

    for axis in axes.T:
        yield PARAMETERS, (moved(-axis), moved(axis))
    if interval is not None:
        # The interval's ends are INTERVAL_Z deviations from the scale: one deviation is that share of the way.
        ends = [scale + (end - scale) / INTERVAL_Z for end in interval]
        yield SCALE, tuple({**run_params, **{n: v for n, v in scaled(estimates, s).items() if torque_power(n)}}
                           for s in ends)


def calibration_spread(rec: Recording, run_params: dict, calibration: dict, correlation: dict, estimates: dict,
                       scale: float, interval: tuple[float, float] | None, place) -> CalibrationSpread:
    """The calibration's variance of each estimate on REC: RUN_PARAMS is the set the estimate ran with
    (Ts and jsf_r_time included), CALIBRATION the per-parameter entries (estimate, lo, hi) with their
    CORRELATION, ESTIMATES the values before the joint's torque SCALE, INTERVAL the scale's (None: a torque
    sensor set it); PLACE(set) places the encoder zero on REC for a set. The smoother's is taken as the
    filter's: a parameter moves both estimates alike, and the smoother's records would cost a kilobyte a
    sample for each run."""
    variance = {std: np.zeros(len(rec.time)) for std in DEVIATIONS.values()}
    share = {PARAMETERS: np.zeros(len(rec.time)), SCALE: np.zeros(len(rec.time))}
    for which, ends in _sets(run_params, calibration, correlation, estimates, scale, interval):
        low, high = (_filtered(rec, place(p)) for p in ends)
        for n in ("tau_ukf", "tau_hat"):
            # Half the difference over one deviation either way; a torque no state explains: no spread known.
            spread_sq = np.nan_to_num((high[n] - low[n]) / 2.0) ** 2
            variance[DEVIATIONS[n]] += spread_sq
            if n == "tau_hat":
                variance[DEVIATIONS["tau_smooth"]] += spread_sq
                share[which] += spread_sq
    return CalibrationSpread(variance, {k: float(np.sqrt(np.mean(v))) for k, v in share.items()})


def _filtered(rec: Recording, params: dict) -> dict[str, np.ndarray]:
    """tau_ukf and tau_hat of the batch engine on REC, fed a block at a time as `hdjoint estimate` feeds it
    (memory: two columns, however long the recording)."""
    out = {name: np.empty(len(rec.time)) for name in ("tau_ukf", "tau_hat")}
    done = 0

    def keep(time, outputs) -> None:
        nonlocal done
        for name, column in out.items():
            column[done:done + len(time)] = outputs[name]
        done += len(time)

    feeder = RowFeeder(CoreEngine(parameters.for_estimator(params), rec.path), params["Ts"], keep)
    inputs = np.column_stack([getattr(rec, name) for name in INPUTS])
    for first in range(0, len(rec.time), CHUNK_ROWS):
        feeder.feed(rec.time[first:first + CHUNK_ROWS], inputs[first:first + CHUNK_ROWS])
    feeder.end_segment()
    return out


def widen_deviations(path: str, spread: CalibrationSpread) -> None:
    """Rewrite the estimates CSV at PATH (a staged file, replaced in one step) with each deviation column
    the root sum of squares of the filter's own and the calibration's; every other cell kept as written."""
    widened = path + ".widened"
    try:
        with open(path, newline="", encoding="utf-8") as src, open(widened, "w", newline="", encoding="utf-8") as dst:
            reader, writer = csv.reader(src), csv.writer(dst, lineterminator="\n")
            header = next(reader)
            writer.writerow(header)
            columns = {header.index(c): v for c, v in spread.variance.items() if c in header}
            samples = len(next(iter(spread.variance.values())))
            rows = 0
            for row in reader:
                if rows < samples:
                    for column, variance in columns.items():
                        row[column] = repr(float(np.sqrt(float(row[column]) ** 2 + variance[rows])))
                writer.writerow(row)
                rows += 1
        if rows != samples:
            raise RuntimeError(f"{path}: {rows} rows for {samples} samples")
        os.replace(widened, path)
    finally:
        if os.path.exists(widened):  # not replaced: nothing half-done is left
            os.unlink(widened)
