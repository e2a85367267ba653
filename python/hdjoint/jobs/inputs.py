"""The user's inputs and outputs, checked before any work: reading
recordings and parameter files with errors that name the file, and refusing
outputs that would overwrite an input or cannot be written."""
from __future__ import annotations

import contextlib
import os
import shutil
from pathlib import Path

from hdjoint.io.outputs import OutputError, OutputLock, check_replaceable, created_directory, printable


class UserError(Exception):
    """Bad input from the user: reported in one line, exit code 2."""


def read_params(path):
    from hdjoint.io import parameters
    try:
        return parameters.load(path)
    except parameters.ParameterError as e:
        raise UserError(str(e)) from None


def read_recording(path, time_unit: str | None = None, current_sign: float = 1.0):
    """The whole recording, its time column converted to seconds from TIME_UNIT
    (None: seconds, with the unit checked for plausibility), its current
    multiplied by CURRENT_SIGN (-1: a current logged against the encoders' sense)."""
    from hdjoint.io.recording import RecordingError, read_recording as read
    from hdjoint.io.timebase import TIME_UNITS, TimeBaseError, check_step
    try:
        rec = read(path)
        rec.time = rec.time * TIME_UNITS[time_unit or "s"]
        rec.i_m = rec.i_m * current_sign
        check_step(str(path), rec.median_step, time_unit)
    except (RecordingError, TimeBaseError) as e:
        raise UserError(str(e)) from None
    return rec


def _same_file(a: Path, b: Path) -> bool:
    try:
        return os.path.samefile(a, b)  # follows links: another path to the same file is caught
    except OSError:
        return False  # one of them does not exist (yet)


def check_output_file(path, inputs=()) -> None:
    """Refuse, before any work, an output file that is one of INPUTS (by any
    path), a directory, or in a missing or unwritable directory."""
    _not_empty(path, "-o")
    out = Path(path)
    for given in inputs:
        if given is not None and _same_file(out, Path(given)):
            raise UserError(f"{path}: is the input {given}; refusing to write over it (choose another output)")
    if out.is_dir():
        raise UserError(f"{path}: is a directory; the output must name a file")
    _check_writable_directory(path, out.absolute().parent)
    _replaceable(out)


def _not_empty(path, option: str) -> None:
    """An empty output path would mean the current folder: refused."""
    if not os.fspath(path).strip():
        raise UserError(f"{option} {printable(repr(os.fspath(path)))}: an empty output path; name a file or folder")


def _replaceable(path: Path) -> None:
    try:
        check_replaceable(path)  # a device node, a FIFO, a read-only file: never replaced
    except OutputError as e:
        raise UserError(str(e)) from None


@contextlib.contextmanager
def locked_output(path):
    """Hold the output PATH (a file or a folder) for the length of a run: a
    second run on the same output is refused (exit 2) instead of racing."""
    try:
        lock = OutputLock(path).acquire()
    except OutputError as e:
        raise UserError(str(e)) from None
    try:
        yield lock
    finally:
        lock.release()


def _check_writable_directory(path, directory: Path) -> None:
    if not directory.is_dir():
        what = "is not a directory" if directory.exists() else "does not exist"
        raise UserError(f"{printable(path)}: the directory {printable(directory)} {what}")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise UserError(f"{printable(path)}: the directory {printable(directory)} is not writable")


def check_output_directory(out, names, inputs=()) -> None:
    """Refuse, before any work, an output directory that is a file, or whose
    NAMES (the files to be written) are directories or inputs; a missing one
    needs a writable existing ancestor (it is created once all is computed)."""
    _not_empty(out, "--out")
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise UserError(f"{out}: exists and is not a directory")
    for name in names:
        target = out / name
        if target.is_dir():
            raise UserError(f"{target}: is a directory, where the file {name} would be written")
        _replaceable(target)
        for given in inputs:
            if given is not None and _same_file(target, Path(given)):
                raise UserError(f"{target}: is the input {given}; refusing to write over it")
    ancestor = out.absolute()
    while not ancestor.exists():
        ancestor = ancestor.parent
    _check_writable_directory(out, ancestor)


@contextlib.contextmanager
def written_folder(out, option: str = "--out"):
    """A folder a command writes (fmus, demo, fleet generate), checked before
    any work (not empty, not a file, in a writable place: else exit 2 naming
    it) and locked for the run; should the run fail, a folder it created goes
    with all it wrote (each file in a folder that was there is written whole
    or not at all)."""
    _not_empty(out, option)
    path = Path(out)
    if path.exists() and not path.is_dir():
        raise UserError(f"{printable(out)}: exists and is not a directory")
    ancestor = path.absolute()
    while not ancestor.exists():
        ancestor = ancestor.parent
    _check_writable_directory(out, ancestor)
    created = created_directory(path)
    with locked_output(path):
        try:
            yield path
        except BaseException:
            if created:
                shutil.rmtree(created[0], ignore_errors=True)
            raise
