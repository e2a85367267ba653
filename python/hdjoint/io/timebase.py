"""A recording's time base: its unit, its sample period against the
estimator's Ts, and the steps that break a fixed sample period (gaps and
jitter). The command line refuses what these find unless told otherwise;
docs/robustness.md states the policy."""
from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

# Seconds per unit of a recording's time column (--time-unit).
TIME_UNITS = {"s": 1.0, "ms": 1e-3, "us": 1e-6}
_UNIT_NAMES = {"s": "seconds", "ms": "milliseconds", "us": "microseconds"}
# Sample periods a joint's sensors are logged at: 100 kHz to 10 Hz. A median
# step outside this range in seconds, but inside it in ms or µs, is a unit slip.
PLAUSIBLE_STEP = (1e-5, 0.1)
# A step this many median steps long is a gap (as the diagnosis has it): samples were lost.
GAP_FACTOR = 10.0
# A step further than this fraction from the median is jitter: the estimator,
# which samples every Ts, would see its inputs at the wrong times.
JITTER_RTOL = 0.2
# The recording's step and the parameters' Ts agree to this fraction.
TS_RTOL = 0.01


def given_ts(params_path) -> float | None:
    """The sample period the parameter file sets, or None when it leaves Ts open."""
    if not params_path:
        return None
    given = json.loads(Path(params_path).read_bytes().decode("utf-8-sig"))  # read_params has validated it
    return float(given["Ts"]) if "Ts" in given else None


def sample_period(median_step: float, given: float | None) -> float:
    """The estimator's Ts: the parameter file's, else the recording's median
    step (to 6 digits, so jitter in the last digits does not change it)."""
    return given if given is not None else float(f"{median_step:.6g}")


class TimeBaseError(ValueError):
    """The time column cannot be what the estimator assumes."""


def likely_unit(step: float) -> str | None:
    """The unit ('ms' or 'us') in which STEP would be a plausible sample period, if any."""
    for unit in ("ms", "us"):
        if PLAUSIBLE_STEP[0] <= step * TIME_UNITS[unit] <= PLAUSIBLE_STEP[1]:
            return unit
    return None


def check_step(where: str, step: float, unit: str | None, ts: float | None = None) -> None:
    """Refuse a median STEP (already in seconds) that is implausible or
    disagrees with the parameters' TS. UNIT is what the user declared (None:
    nothing, seconds assumed); a declared unit must give a plausible step too."""
    lo, hi = PLAUSIBLE_STEP
    if unit is not None and not lo <= step <= hi:
        raw = step / TIME_UNITS[unit]  # the step as the file writes it
        guess = next((u for u in TIME_UNITS if u != unit and lo <= raw * TIME_UNITS[u] <= hi), None)
        hint = (f"the time column looks like {_UNIT_NAMES[guess]}: "
                + ("leave --time-unit out" if guess == "s" else f"pass --time-unit {guess}") if guess
                else "check the time column's unit")
        raise TimeBaseError(f"{where}: with --time-unit {unit} the median time step is {step:.6g} s, implausible "
                            f"for a joint recording (expected {lo:g} to {hi:g} s); {hint}")
    if unit is None and not lo <= step <= hi:
        guess = likely_unit(step)
        hint = (f"the time column looks like {_UNIT_NAMES[guess]}: pass --time-unit {guess}" if guess
                else "check the time column's unit (--time-unit s, ms or us)")
        raise TimeBaseError(f"{where}: the median time step is {step:.6g}, implausible as seconds for a joint "
                            f"recording (expected {lo:g} to {hi:g} s); {hint}")
    if ts is not None and abs(step - ts) > TS_RTOL * ts:
        ratio = step / ts
        guess = next((u for u, f in TIME_UNITS.items() if u != (unit or "s")
                      and abs(ratio * f / TIME_UNITS[unit or "s"] - 1) <= TS_RTOL), None)
        hint = f"; the time column looks like {_UNIT_NAMES[guess]}: pass --time-unit {guess}" if guess else ""
        raise TimeBaseError(f"{where}: the recording's median step {step:.6g} s does not match the parameters' "
                            f"Ts = {ts:g} s{hint}")


@dataclass(frozen=True)
class IrregularStep:
    """The step from row `index` to row `index + 1` (0-based rows of the data)."""
    index: int
    start: float   # time of row `index`, s
    length: float  # s
    kind: str      # "gap" or "jitter"


def irregular_steps(time: np.ndarray, step: float, previous: float | None = None) -> list[IrregularStep]:
    """Steps of TIME (continuing after PREVIOUS, the last time before it, if
    any) that are gaps or jitter against the median STEP. Index -1 is the step
    from PREVIOUS into the block."""
    t = np.asarray(time, float) if previous is None else np.concatenate(([previous], time))
    offset = 0 if previous is None else -1
    dt = np.diff(t)
    bad = np.flatnonzero(np.abs(dt - step) > JITTER_RTOL * step)
    return [IrregularStep(int(k) + offset, float(t[k]), float(dt[k]),
                          "gap" if dt[k] > GAP_FACTOR * step else "jitter") for k in bad]


def describe(step: IrregularStep, line_before: int, line_after: int, median: float) -> str:
    what = "a gap" if step.kind == "gap" else "a jittered step"
    return (f"{what} of {step.length:.6g} s after t = {step.start:.9g} s (lines {line_before} to {line_after}; "
            f"the median step is {median:.6g} s)")
