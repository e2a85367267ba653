"""Reading and writing recordings in the contract's CSV format.

A recording is a CSV file with one header row, SI units and one row per
sample, time strictly increasing.  Required columns: ``time``, ``i_m``,
``theta_m``, ``theta_l``; optional: ``tau_sensor``.  Any other column is kept
(in ``Recording.extra``) and otherwise ignored.

A malformed file raises one ``RecordingError`` naming the file and, where it
applies, the 1-based line (the header is line 1) and the column; never the
file's contents (a recording may be a link to a file that is not one, and
the message reaches pages and tables). A line longer than MAX_LINE
characters is refused as it is read: memory stays bounded whatever the file.
"""

from __future__ import annotations

import csv
import math
import os
import warnings
from dataclasses import dataclass, field
from typing import Iterable, Iterator, Mapping, Sequence

import numpy as np

from hdjoint.io.outputs import check_replaceable, open_temp, printable, replace_into, sweep_debris, write_error

REQUIRED_COLUMNS = ("time", "i_m", "theta_m", "theta_l")
OPTIONAL_COLUMNS = ("tau_sensor",)
# Columns the tools compute with: these must be numbers and finite.
KNOWN_COLUMNS = REQUIRED_COLUMNS + OPTIONAL_COLUMNS
MIN_ROWS = 2
# The longest line read, in characters: a row of a recording is tens of characters, a header hundreds.
MAX_LINE = 1 << 16
# The largest magnitude a computed-with column may hold: the FMUs' input range. Beyond it (a 1e308), the
# arithmetic would overflow far from its line; within it, a wild sample is screened (io/screening.py).
MAX_MAGNITUDE = 1e300
BLOCK_CHARS = 1 << 25  # the most text one block holds (32 M characters), however long its lines

__all__ = [
    "REQUIRED_COLUMNS",
    "OPTIONAL_COLUMNS",
    "Recording",
    "RecordingError",
    "read_recording",
    "iter_recording",
    "write_csv",
    "CsvWriter",
    "write_recording",
]


class RecordingError(ValueError):
    """A recording that cannot be read.

    The message always starts with the file name, then the line and column
    when the problem has one, e.g.
    ``data.csv: line 17, column theta_l: not a number``.
    """

    def __init__(self, path, reason: str, line: int | None = None,
                 column: str | None = None):
        self.path = os.fspath(path) if path is not None else None
        self.reason = reason
        self.line = line
        self.column = column
        where = []
        if line is not None:
            where.append(f"line {line}")
        if column is not None:
            where.append(f"column {column}")
        prefix = f"{printable(self.path)}: " + (", ".join(where) + ": " if where else "")
        super().__init__(prefix + reason)

    def __reduce__(self):
        # Keep the exception picklable (e.g. across multiprocessing) despite
        # the custom constructor signature.
        return (type(self), (self.path, self.reason, self.line, self.column))


def _float_array(values, name: str) -> np.ndarray:
    arr = np.asarray(values, dtype=float)
    if arr.ndim != 1:
        raise ValueError(f"{name} must be one-dimensional, got shape {arr.shape}")
    return arr


@dataclass
class Recording:
    """One recording: the contract's columns as float arrays, plus extras."""

    time: np.ndarray
    i_m: np.ndarray
    theta_m: np.ndarray
    theta_l: np.ndarray
    tau_sensor: np.ndarray | None = None
    extra: dict[str, np.ndarray] = field(default_factory=dict)
    path: str | None = None

    def __post_init__(self):
        # Normalise to 1-D float arrays so callers may pass lists, and catch
        # mismatched lengths here rather than deep inside an estimator.
        for name in KNOWN_COLUMNS:
            value = getattr(self, name)
            if value is not None:
                setattr(self, name, _float_array(value, name))
        self.extra = {k: np.asarray(v) for k, v in self.extra.items()}
        n = len(self.time)
        for name, col in self.columns().items():
            if len(col) != n:
                raise ValueError(
                    f"column {name} has {len(col)} samples, time has {n}")

    def columns(self) -> dict[str, np.ndarray]:
        """All columns in file order: contract columns first, then extras."""
        cols = {name: getattr(self, name) for name in KNOWN_COLUMNS}
        cols = {k: v for k, v in cols.items() if v is not None}
        cols.update(self.extra)
        return cols

    def __len__(self) -> int:
        return len(self.time)

    def __repr__(self) -> str:
        n = len(self)
        rate = ""
        if n > 1:
            hz = round(1.0 / self.median_step, 6)
            rate = f" at {hz / 1000:g} kHz" if hz >= 1000 else f" at {hz:g} Hz"
        names = list(self.columns())
        shown = ", ".join(names[:5]) + (", ..." if len(names) > 5 else "")
        return f"Recording({self.path or 'in memory'}: {n} samples, {self.duration:.4g} s{rate}; {shown})"

    def save(self, path) -> None:
        """Write the recording as a contract CSV (write_recording)."""
        write_recording(path, self)

    @property
    def duration(self) -> float:
        """Time from the first to the last sample, s."""
        return float(self.time[-1] - self.time[0]) if len(self) else 0.0

    @property
    def median_step(self) -> float:
        """Median sample period, s (robust to the odd dropped sample)."""
        if len(self) < 2:
            raise ValueError("median_step needs at least 2 samples")
        return float(np.median(np.diff(self.time)))

    def sample_times_regular(self, rtol: float = 1e-3) -> bool:
        """True when every step is within ``rtol`` of the median step.

        The estimators assume a fixed sample period; this tells whether the
        recording honours it.
        """
        step = self.median_step
        return bool(np.all(np.abs(np.diff(self.time) - step) <= rtol * step))

    def slice(self, start: int | None = None, stop: int | None = None) -> "Recording":
        """Samples ``start:stop`` (Python index semantics) as a new Recording.

        The arrays are copies, so editing the slice leaves this one intact.
        """
        sel = slice(start, stop)

        def cut(a):
            return None if a is None else a[sel].copy()

        return Recording(
            time=cut(self.time), i_m=cut(self.i_m), theta_m=cut(self.theta_m),
            theta_l=cut(self.theta_l), tau_sensor=cut(self.tau_sensor),
            extra={k: cut(v) for k, v in self.extra.items()}, path=self.path)


# --------------------------------------------------------------------------
# Reading


def _check_header(path: str, header: list[str]) -> list[str]:
    """The column names; a message names only the contract's own (the others are the file's contents)."""
    names = [name.strip() for name in header]
    seen: dict[str, int] = {}
    for i, name in enumerate(names, start=1):
        if not name:
            raise RecordingError(path, f"column {i} has an empty name", line=1)
        if name in seen:
            raise RecordingError(
                path, f"duplicate column name (columns {seen[name]} and {i})",
                line=1, column=name if name in KNOWN_COLUMNS else None)
        seen[name] = i
    missing = [c for c in REQUIRED_COLUMNS if c not in seen]
    if missing:
        known = [n for n in names if n in KNOWN_COLUMNS]
        others = len(names) - len(known)
        found = ", ".join(known + ([f"{others} other column{'s' if others > 1 else ''}"] if others else []))
        raise RecordingError(
            path, f"missing required column{'s' if len(missing) > 1 else ''} "
                  f"{', '.join(missing)} (found: {found}; is this a recording?)", line=1)
    return names


def _check_row_lengths(path, rows, lines, width):
    for row, line in zip(rows, lines):
        if len(row) != width:
            raise RecordingError(
                path, f"expected {width} fields (as in the header), found {len(row)}",
                line=line)


def _number(cell: str) -> float:
    # float() also takes Python literal syntax such as '1_000'; in a data
    # file that is far likelier a typo than a number, and np.loadtxt (the
    # fast path) rejects it too, so both loaders agree.
    if "_" in cell:
        raise ValueError(cell)
    return float(cell)


def _first_bad_cell(cells: Sequence[str]) -> tuple[int, str] | None:
    """Index and reason of the first cell that is not a finite number."""
    for i, cell in enumerate(cells):
        try:
            value = _number(cell)
        except ValueError:
            return i, "not a number" if cell.strip() else "empty, not a number"
        if not math.isfinite(value):
            return i, "not a finite number (nan or inf)"
        if abs(value) > MAX_MAGNITUDE:
            return i, f"too large a number (over {MAX_MAGNITUDE:g} in size) for a measurement"
    return None


def _parse_known_columns(path, names, columns, lines) -> dict[str, np.ndarray]:
    """Convert the contract's columns; report the earliest bad cell in the file."""
    parsed, problems = {}, []
    for name in KNOWN_COLUMNS:
        if name not in names:
            continue
        cells = columns[names.index(name)]
        try:
            arr = np.fromiter(map(_number, cells), dtype=float, count=len(cells))
            ok = bool((np.abs(arr) <= MAX_MAGNITUDE).all())  # NaN fails too
        except ValueError:
            ok = False
        if ok:
            parsed[name] = arr
        else:
            # Slow scan only on failure, to locate the exact cell.
            index, reason = _first_bad_cell(cells)
            problems.append((index, KNOWN_COLUMNS.index(name), name, reason))
    if problems:
        index, _, name, reason = min(problems)
        raise RecordingError(path, reason, line=lines[index], column=name)
    return parsed


def _parse_extra_column(cells: Sequence[str]) -> np.ndarray:
    # Extras are "kept and ignored": numbers when they all parse, else text,
    # but never a reason to reject the file.
    try:
        return np.fromiter(map(_number, cells), dtype=float, count=len(cells))
    except ValueError:
        return np.array([c.strip() for c in cells], dtype=str)


def _check_time(path, time, lines):
    bad = np.flatnonzero(np.diff(time) <= 0)
    if bad.size:
        k = int(bad[0]) + 1
        raise RecordingError(
            path, f"not after the time on line {lines[k - 1]} (time must be strictly increasing)",
            line=lines[k], column="time")


def _open(path: str):
    try:
        # utf-8-sig: tolerate the byte-order mark spreadsheet programs write.
        return open(path, encoding="utf-8-sig", newline="")
    except FileNotFoundError:
        raise RecordingError(path, "file not found") from None
    except IsADirectoryError:
        raise RecordingError(path, "is a directory, not a file") from None
    except OSError as exc:
        raise RecordingError(path, f"cannot read file: {exc.strerror or exc}") from None


def _read_lines(path: str, f, count: int, first_line: int) -> list[str]:
    """Up to COUNT lines from F, FIRST_LINE the first's number; a line over MAX_LINE characters is refused."""
    lines, size = [], 0
    try:
        for line in iter(lambda: f.readline(MAX_LINE + 2), ""):
            if len(line) > MAX_LINE and len(line.rstrip("\r\n")) > MAX_LINE:
                raise RecordingError(path, f"longer than {MAX_LINE} characters; a recording's lines are far shorter "
                                           "(is this a recording?)", line=first_line + len(lines))
            lines.append(line)
            size += len(line)
            if len(lines) == count or size >= BLOCK_CHARS:  # a block of long lines ends early
                break
        return lines
    except UnicodeDecodeError as exc:
        raise RecordingError(path, f"not UTF-8 text ({exc.reason} at byte {exc.start} of a block)") from None
    except OSError as exc:
        raise RecordingError(path, f"cannot read file: {exc.strerror or exc}") from None


def _read_header(path: str, f) -> list[str]:
    first = _read_lines(path, f, 1, 1)
    if not first or not first[0].strip():
        rest = _read_lines(path, f, 1 << 16, 2)
        if any(line.strip() for line in rest):
            # Keep the "header is line 1" promise honest when blank lines lead.
            raise RecordingError(path, "header row must be the first line",
                                 line=2 + next(i for i, line in enumerate(rest) if line.strip()))
        raise RecordingError(path, "file is empty (no header row)")
    try:
        header = next(csv.reader(first))
    except csv.Error as exc:
        raise RecordingError(path, f"malformed CSV: {exc}", line=1) from None
    return _check_header(path, header)


def _chunk_fast(names, lines: list[str]) -> dict[str, np.ndarray] | None:
    """Columns of a well-formed, all-numeric block, or None on any doubt.

    np.loadtxt parses in C, several times faster than csv + float() per
    cell.  It cannot say which line is wrong, so on any doubt (quotes, blank
    lines, text columns, bad values, bad time order, ...) the checked parser,
    which produces every error message, takes over.
    """
    if '"' in "".join(lines):
        return None
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            data = np.loadtxt(lines, delimiter=",", comments=None, dtype=float, ndmin=2)
    except ValueError:
        return None
    if data.shape != (len(lines), len(names)):  # e.g. a blank line: the line numbers would shift
        return None
    columns = dict(zip(names, np.ascontiguousarray(data.T)))
    if not all((np.abs(columns[name]) <= MAX_MAGNITUDE).all() for name in KNOWN_COLUMNS if name in columns):
        return None
    if not (np.diff(columns["time"]) > 0).all():
        return None
    return columns


def _chunk_checked(path, names, lines: list[str], first_line: int):
    """Cell-by-cell parse of a block that pinpoints its first problem."""
    reader = csv.reader(lines)
    rows, numbers = [], []
    try:
        for row in reader:
            if row:
                rows.append(row)
                numbers.append(first_line + reader.line_num - 1)
    except csv.Error as exc:
        raise RecordingError(path, f"malformed CSV: {exc}", line=first_line + reader.line_num - 1) from None
    if not rows:
        return {}, []
    _check_row_lengths(path, rows, numbers, len(names))
    columns = list(zip(*rows))
    known = _parse_known_columns(path, names, columns, numbers)
    _check_time(path, known["time"], numbers)
    known.update({name: _parse_extra_column(columns[i]) for i, name in enumerate(names) if name not in KNOWN_COLUMNS})
    return known, numbers


@dataclass
class Chunk:
    """A block of consecutive samples of a recording, with their 1-based lines."""
    recording: Recording
    lines: np.ndarray


CHUNK_ROWS = 1 << 16  # ~5 MB of text a block: memory stays flat whatever the file's length


def iter_recording(path, rows: int = CHUNK_ROWS) -> Iterator[Chunk]:
    """A recording block by block, with every check of ``read_recording``
    (time increasing across blocks too); memory stays that of one block.

    A malformed block raises RecordingError when it is reached, so a caller
    that writes as it reads must write to a temporary file (as write_csv does).
    """
    path = os.fspath(path)
    with _open(path) as f:
        names = _read_header(path, f)
        next_line, last, total = 2, None, 0
        while lines := _read_lines(path, f, rows, next_line):
            columns = _chunk_fast(names, lines)
            numbers = np.arange(next_line, next_line + len(lines))
            if columns is None:
                columns, numbers = _chunk_checked(path, names, lines, next_line)
            next_line += len(lines)
            if len(numbers) == 0:
                continue
            time = columns["time"]
            if last is not None and time[0] <= last[0]:
                raise RecordingError(
                    path, f"time {float(time[0])!r} is not after {last[0]!r} on line {last[1]} "
                          "(time must be strictly increasing)", line=int(numbers[0]), column="time")
            last = (float(time[-1]), int(numbers[-1]))
            total += len(time)
            known = {name: columns.pop(name) for name in KNOWN_COLUMNS if name in columns}
            yield Chunk(Recording(extra=columns, path=path, **known), np.asarray(numbers))
    if total < MIN_ROWS:
        raise RecordingError(path, f"needs at least {MIN_ROWS} rows of data, found {total}")


def _joined(parts: list[np.ndarray]) -> np.ndarray:
    if len({p.dtype.kind for p in parts}) > 1:
        # An extra column numeric in one block and text in another: text, as
        # a one-block file would give (extras are kept, never checked).
        parts = [p.astype(str) for p in parts]
    return np.concatenate(parts)


def read_recording(path) -> Recording:
    """Read a recording CSV; raise RecordingError if it is malformed."""
    chunks = [c.recording for c in iter_recording(path)]
    columns = {name: _joined([c.columns()[name] for c in chunks]) for name in chunks[0].columns()}
    known = {name: columns.pop(name) for name in KNOWN_COLUMNS if name in columns}
    return Recording(extra=columns, path=os.fspath(path), **known)


# --------------------------------------------------------------------------
# Writing


def _format_column(name: str, values) -> list[str]:
    arr = np.asarray(values)
    if arr.ndim != 1:
        raise ValueError(f"column {name!r} must be one-dimensional, got shape {arr.shape}")
    if arr.dtype.kind in "fiub":
        # repr of a Python float is the shortest text that reads back to the
        # identical double: full precision without '%.17g' noise.
        return list(map(repr, arr.astype(float).tolist()))
    if arr.dtype.kind in "UO":
        # Text (e.g. a label column) passes through; anything else numeric-
        # like is converted the same way as floats.
        return [v if isinstance(v, str) else repr(float(v)) for v in arr.tolist()]
    raise ValueError(f"column {name!r} has unsupported dtype {arr.dtype}")


def _validated_columns(path, columns: Mapping[str, Iterable]) -> dict[str, list[str]]:
    if not columns:
        raise ValueError(f"{path}: no columns to write")
    formatted = {}
    first = None
    for name, values in columns.items():
        if not isinstance(name, str) or not name.strip():
            raise ValueError(f"{path}: column name {name!r} is not a non-empty string")
        cells = _format_column(name, values)
        if first is None:
            first = (name, len(cells))
        elif len(cells) != first[1]:
            raise ValueError(
                f"{path}: column {name!r} has {len(cells)} values but column "
                f"{first[0]!r} has {first[1]}; all columns must have the same length")
        formatted[name] = cells
    return formatted


class CsvWriter:
    """A CSV written block by block into a temporary file next to PATH, which
    replaces PATH in one step on success: readers never see a half-written
    file, and on any error neither partial output nor the temporary file is
    left. Errors name PATH, never the temporary file.

        with CsvWriter(path, names) as out:
            out.write(columns)   # as often as needed
    """

    def __init__(self, path, names: Sequence[str]):
        self.path = os.fspath(path)
        self.names = list(names)
        sweep_debris(self.path)  # what a run killed outright (SIGKILL) left behind
        try:
            # O_EXCL and O_NOFOLLOW: never a stranger's file or a link; 0o666 lets
            # the umask decide the final permissions, as for a normally created file.
            self._file, self._tmp = open_temp(self.path)
        except OSError as exc:
            raise write_error(self.path, exc) from None
        try:  # from here the temporary file is ours to remove, even if a signal stops us before `with` is entered
            self._writer = csv.writer(self._file, lineterminator="\n")
            self._guard(self._writer.writerow, self.names)
        except BaseException:
            self.discard()
            raise

    def _guard(self, fn, *args):
        try:
            return fn(*args)
        except OSError as exc:
            self.discard()
            raise write_error(self.path, exc) from None

    def write(self, columns: Mapping[str, Iterable]) -> None:
        """Append rows: every name of the header, equal lengths."""
        if list(columns) != self.names:
            raise ValueError(f"{self.path}: columns {list(columns)} are not the header's {self.names}")
        self.write_cells(_validated_columns(self.path, columns))

    def write_cells(self, formatted: Mapping[str, list[str]]) -> None:
        """Append rows already formatted by _validated_columns."""
        self._guard(self._writer.writerows, zip(*formatted.values()))

    def commit(self) -> None:
        def finish():
            self._file.flush()
            os.fsync(self._file.fileno())
            self._file.close()
            check_replaceable(self.path)  # again: it may have changed while we computed
            replace_into(self._tmp, self.path)  # an existing file keeps its mode
        try:
            self._guard(finish)
        except ValueError:
            self.discard()
            raise

    def discard(self) -> None:
        try:
            if self._file is not None:
                self._file.close()  # flushes: on a full disk this fails too, and the file goes all the same
        except OSError:
            pass
        try:
            os.unlink(self._tmp)
        except FileNotFoundError:
            pass

    def __enter__(self):
        return self

    def __exit__(self, exc_type, exc, tb):
        # BaseException too: a Ctrl-C mid-write must not leave the temp file.
        if exc_type is None:
            self.commit()
        else:
            self.discard()


def write_csv(path, columns: Mapping[str, Iterable]) -> None:
    """Write named columns as a CSV with full float precision, atomically (see CsvWriter)."""
    path = os.fspath(path)
    # Format everything first: most errors surface before touching the disk.
    formatted = _validated_columns(path, columns)
    with CsvWriter(path, list(formatted)) as out:
        out.write_cells(formatted)


def write_recording(path, rec: Recording) -> None:
    """Write a Recording in the contract format (extras after the contract columns)."""
    clash = set(rec.extra) & set(KNOWN_COLUMNS)
    if clash:
        raise ValueError(f"{os.fspath(path)}: extra columns {sorted(clash)} "
                         "clash with contract column names")
    write_csv(path, rec.columns())
