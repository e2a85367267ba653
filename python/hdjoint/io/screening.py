"""Screening a recording before it is analysed: what makes it unusable
(refused, naming the reason), and single wild samples (outliers), found in
every channel and left out.

Refused (`Degenerate`): a channel that never varies (a recording of zeros, a
current that is never commanded, an encoder that never moves), and an angle
that jumps by more than half a turn from one sample to the next (an encoder
that wraps at +-pi: the contract's angles are multi-turn).

An outlier is a sample that stands far from what its neighbours say it is
(the median of the nine straight lines through one of the three samples
before it and one of the three after, read at its time), both in the
channel's own noise (OUTLIER_Z robust standard deviations of that distance:
the median absolute distance, scaled) and in its resolution (OUTLIER_COUNTS
of the smallest step the channel takes, so a quantised encoder at rest,
whose distance is mostly zero, is not flagged for one count). The lines
follow ramps, sinusoids sampled at the recording's rate and an irregular
clock; a step (a new current command, a load) stands out of the lines
across it, so a sample must also stand out of the running median of five
samples, which follows steps. Only isolated samples (up to two in a row)
stand out of both. And a fast oscillation's peaks stand out of their lines,
so a sample must stand out by OUTLIER_BENDS times how sharply the signal
turns around it (the running median of its second difference over LOCAL
samples, which a wild sample or two does not move). A sample so found is left out: replaced by the
straight line between the nearest kept samples of the same channel, so the
time base stays regular. docs/diagnosis.md, "Screening"."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hdjoint.io.recording import Recording

CHANNELS = ("i_m", "theta_m", "theta_l", "tau_sensor")
UNITS = {"i_m": "A", "theta_m": "rad", "theta_l": "rad", "tau_sensor": "N.m"}
NEIGHBOURS = 3          # samples on each side a sample is compared with: a run of two wild samples stands out
OUTLIER_Z = 12.0        # robust standard deviations of the distance to the running median
OUTLIER_COUNTS = 20.0   # steps of the channel's resolution
OUTLIER_BENDS = 8.0     # times the signal's own local second difference
LOCAL = 21              # samples over which that is taken
# More outliers than this share of the samples is not a wild sample or two
# but the channel's own sharp features (a controller's D-term answering each
# encoder count, a current loop's ripple): the channel is kept as recorded.
MAX_OUTLIER_SHARE = 0.001
MIN_OUTLIERS_ALLOWED = 10
WRAP_JUMP = math.pi     # rad between consecutive samples: an encoder that wraps


class Degenerate(ValueError):
    """A recording from which nothing can be said; the message names the file and the reason."""


@dataclass(frozen=True)
class Outlier:
    channel: str
    row: int        # 0-based data row
    line: int       # 1-based line of the file (the header is line 1)
    time: float     # s
    value: float    # as recorded
    replaced_by: float


@dataclass
class Screening:
    """What screening found in one recording."""
    path: str | None
    outliers: list[Outlier] = field(default_factory=list)
    # Channels with too many sharp samples to be wild ones: kept as recorded (channel -> how many).
    kept_as_recorded: dict[str, int] = field(default_factory=dict)

    def counts(self) -> dict[str, int]:
        found = {name: 0 for name in CHANNELS}
        for o in self.outliers:
            found[o.channel] += 1
        return {k: v for k, v in found.items() if v}

    def as_dict(self, listed: int = 20) -> dict:
        """For findings.json: counts per channel and the first LISTED outliers (strict JSON)."""
        return {"recording": self.path, "outliers_left_out": len(self.outliers), "by_channel": self.counts(),
                "summary": self.summary(), "kept_as_recorded": dict(self.kept_as_recorded),
                "outliers": [{"channel": o.channel, "line": o.line, "time": o.time,
                              "value": _json_number(o.value), "replaced_by": o.replaced_by}
                             for o in self.outliers[:listed]]}

    def summary(self) -> str:
        """One sentence: how many outliers, in which channels, where (the first lines)."""
        kept = "; ".join(f"{channel} kept as recorded: {n} sharp samples are its own, not a few wild ones"
                         for channel, n in self.kept_as_recorded.items())
        if not self.outliers:
            return kept or "no outliers"
        parts = []
        for channel, n in self.counts().items():
            lines = [o.line for o in self.outliers if o.channel == channel]
            shown = ", ".join(map(str, lines[:5])) + (", ..." if len(lines) > 5 else "")
            parts.append(f"{n} in {channel} (line{'s' if n > 1 else ''} {shown})")
        left_out = f"{len(self.outliers)} outlier{'s' if len(self.outliers) > 1 else ''} left out: " + "; ".join(parts)
        return f"{left_out}; {kept}" if kept else left_out


def found_anything(entry: dict) -> bool:
    """A findings.json screening entry says more than "no outliers"."""
    return bool(entry["outliers_left_out"] or entry.get("kept_as_recorded"))


def _json_number(x: float):
    return x if math.isfinite(x) else None


def strict_json(value):
    """VALUE with numpy numbers made Python ones and every non-finite number
    made None, so json.dumps(..., allow_nan=False) writes strict JSON."""
    if isinstance(value, dict):
        return {k: strict_json(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [strict_json(v) for v in value]
    if isinstance(value, np.ndarray):
        return [strict_json(v) for v in value.tolist()]
    if isinstance(value, (bool, np.bool_)):
        return bool(value)
    if isinstance(value, (int, np.integer)):
        return int(value)
    if isinstance(value, (float, np.floating)):
        return float(value) if math.isfinite(value) else None
    return value


def _where(rec: Recording) -> str:
    return rec.path or "recording"


def check_not_degenerate(rec: Recording, channels=("i_m", "theta_m", "theta_l")) -> None:
    """Refuse a recording whose CHANNELS never vary, or whose angles wrap."""
    where = _where(rec)
    for name in channels:
        x = getattr(rec, name)
        if x is None:
            continue
        if float(np.max(x) - np.min(x)) == 0.0:
            what = {"i_m": "the motor current never varies (no current was commanded)",
                    "theta_m": "the motor encoder never moves", "theta_l": "the link encoder never moves"}[name]
            raise Degenerate(f"{where}: column {name}: {what} (every sample is {float(x[0]):g}); "
                             "nothing about the joint can be told from it")
    check_no_wrap(rec)


def _wraps(steps: np.ndarray) -> np.ndarray:
    """The steps that are a wrap: over half a turn, and one that a whole
    number of turns taken off makes like the steps around it (a fast motor
    logged slowly takes large steps too, but they are all alike)."""
    big = np.flatnonzero(np.abs(steps) > WRAP_JUMP)
    wraps = []
    for k in big:
        unwrapped = steps[k] - 2 * math.pi * round(steps[k] / (2 * math.pi))
        around = np.concatenate((steps[max(k - 2, 0):k], steps[k + 1:k + 3]))
        if not len(around) or abs(unwrapped - float(np.median(around))) < WRAP_JUMP / 2:
            wraps.append(k)
    return np.asarray(wraps, int)


def check_no_wrap(rec: Recording, lines=None, previous: dict | None = None) -> None:
    """Refuse an angle of REC that jumps by more than WRAP_JUMP between
    samples (LINES: the rows' file lines, default row + 2; PREVIOUS: the
    angles of the row before REC, when it is a block of a longer file)."""
    for name in ("theta_m", "theta_l"):
        x = getattr(rec, name)
        if previous is not None:
            x = np.concatenate(([previous[name]], x))
        jumps = _wraps(np.diff(x))
        if len(jumps):
            k = int(jumps[0]) - (previous is not None)  # the row after the jump is k + 1
            line = int(lines[k + 1]) if lines is not None else k + 3
            step = float(x[jumps[0] + 1] - x[jumps[0]])
            raise Degenerate(f"{_where(rec)}: line {line}, column {name}: the angle jumps by {step:+.4g} rad from "
                             "one sample to the next: the encoder wraps at +-pi; angles must be multi-turn (unwrap "
                             "them, e.g. numpy.unwrap): nothing can be said of the joint from a wrapped angle")


def _resolution(x: np.ndarray) -> float:
    """The smallest step the channel takes (its quantum, for an encoder), robustly: the 1st percentile of the
    nonzero steps."""
    steps = np.abs(np.diff(x))
    steps = steps[steps > 0]
    return float(np.percentile(steps, 1)) if len(steps) else 0.0


_PAIRS = [(i, j) for i in range(1, NEIGHBOURS + 1) for j in range(1, NEIGHBOURS + 1)]
_BLOCK = 1 << 16


def distance_to_neighbours(time: np.ndarray, x: np.ndarray) -> np.ndarray:
    """|x - what its neighbours say it is|: the median of the straight lines
    through one of the NEIGHBOURS samples before and one of those after,
    read at the sample's time (exact on a ramp, also on an irregular clock;
    a wild neighbour spoils fewer than half the lines). Zero at the ends."""
    n, m = len(x), NEIGHBOURS
    d = np.zeros(n)
    for start in range(m, n - m, _BLOCK):
        k = np.arange(start, min(start + _BLOCK, n - m))
        lines = np.empty((len(_PAIRS), len(k)))
        for row, (i, j) in enumerate(_PAIRS):
            a, b = k - i, k + j
            lines[row] = x[a] + (x[b] - x[a]) * ((time[k] - time[a]) / (time[b] - time[a]))
        d[k] = np.abs(x[k] - np.median(lines, axis=0))
    return d


def find_outliers(x: np.ndarray, time: np.ndarray | None = None) -> np.ndarray:
    """Indices of the wild samples of X (see the module's rule)."""
    x = np.asarray(x, float)
    time = np.arange(len(x), dtype=float) if time is None else np.asarray(time, float)
    if len(x) < 2 * NEIGHBOURS + 1:
        return np.zeros(0, int)
    # Scaled into a safe range first: a sample of 1e300 must not overflow the arithmetic.
    scale = float(np.median(np.abs(x))) or 1.0
    y = np.clip(x / scale, -1e150, 1e150)
    from scipy.ndimage import median_filter
    lines = distance_to_neighbours(time, y)
    sigma = 1.4826 * float(np.median(lines[NEIGHBOURS:-NEIGHBOURS]))
    # A step (a current command, a load) is far from the lines across it, but not from its running median:
    # a wild sample is far from both.
    distance = np.minimum(lines, np.abs(y - median_filter(y, size=2 * NEIGHBOURS - 1, mode="nearest")))
    # How sharply the signal itself turns there (a fast oscillation's peaks stand out of their lines too):
    # the running median of its second difference over LOCAL samples, which one wild sample does not move.
    bend = np.abs(np.diff(y, 2, prepend=y[0], append=y[-1]))
    local = median_filter(bend, size=LOCAL, mode="nearest")
    threshold = np.maximum(max(OUTLIER_Z * sigma, OUTLIER_COUNTS * _resolution(y)), OUTLIER_BENDS * local)
    return np.flatnonzero((distance > threshold) & (threshold > 0))


def _fill(x: np.ndarray, bad: np.ndarray) -> np.ndarray:
    """X with the samples BAD replaced by the straight line between the nearest kept samples."""
    keep = np.ones(len(x), bool)
    keep[bad] = False
    idx = np.arange(len(x))
    out = x.copy()
    out[bad] = np.interp(idx[bad], idx[keep], x[keep])
    return out


def screen(rec: Recording, line_of=None) -> tuple[Recording, Screening]:
    """A copy of REC with each channel's outliers left out, and what was found.
    LINE_OF maps a 0-based row to the file's line (default: row + 2)."""
    line_of = line_of or (lambda row: row + 2)
    found = Screening(rec.path)
    columns = {}
    for name in CHANNELS:
        x = getattr(rec, name)
        if x is None:
            continue
        bad = find_outliers(x, rec.time)
        limit = max(MIN_OUTLIERS_ALLOWED, int(MAX_OUTLIER_SHARE * len(x)))
        if len(bad) > limit:
            found.kept_as_recorded[name] = len(bad)
            continue
        if len(bad):
            filled = _fill(x, bad)
            found.outliers += [Outlier(name, int(k), int(line_of(int(k))), float(rec.time[k]), float(x[k]),
                                       float(filled[k])) for k in bad]
            columns[name] = filled
    found.outliers.sort(key=lambda o: (o.row, CHANNELS.index(o.channel)))
    if not columns:
        return rec, found
    kept = {name: columns.get(name, getattr(rec, name)) for name in CHANNELS}
    cleaned = Recording(time=rec.time.copy(), extra=dict(rec.extra), path=rec.path, **kept)
    return cleaned, found
