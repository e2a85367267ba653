"""Whole jobs from files to files, shared by the command line and the demo
(which call these, never each other): reading the user's inputs with errors
that name the file, and one diagnosis written into its directory."""
from __future__ import annotations

import os
import sys
from pathlib import Path


class UserError(Exception):
    """Bad input from the user: reported in one line, exit code 2."""


def read_params(path):
    from . import parameters
    try:
        return parameters.load(path)
    except parameters.ParameterError as e:
        raise UserError(str(e)) from None


def read_recording(path, time_unit: str | None = None):
    """The whole recording, its time column converted to seconds from TIME_UNIT
    (None: seconds, with the unit checked for plausibility)."""
    from .recording import RecordingError, read_recording as read
    from .timebase import TIME_UNITS, TimeBaseError, check_step
    try:
        rec = read(path)
        rec.time = rec.time * TIME_UNITS[time_unit or "s"]
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
    out = Path(path)
    for given in inputs:
        if given is not None and _same_file(out, Path(given)):
            raise UserError(f"{path}: is the input {given}; refusing to write over it (choose another output)")
    if out.is_dir():
        raise UserError(f"{path}: is a directory; the output must name a file")
    _check_writable_directory(path, out.absolute().parent)


def _check_writable_directory(path, directory: Path) -> None:
    if not directory.is_dir():
        what = "is not a directory" if directory.exists() else "does not exist"
        raise UserError(f"{path}: the directory {directory} {what}")
    if not os.access(directory, os.W_OK | os.X_OK):
        raise UserError(f"{path}: the directory {directory} is not writable")


def check_output_directory(out, names, inputs=()) -> None:
    """Refuse, before any work, an output directory that is a file, or whose
    NAMES (the files to be written) are directories or inputs; a missing one
    needs a writable existing ancestor (it is created once all is computed)."""
    out = Path(out)
    if out.exists() and not out.is_dir():
        raise UserError(f"{out}: exists and is not a directory")
    for name in names:
        target = out / name
        if target.is_dir():
            raise UserError(f"{target}: is a directory, where the file {name} would be written")
        for given in inputs:
            if given is not None and _same_file(target, Path(given)):
                raise UserError(f"{target}: is the input {given}; refusing to write over it")
    ancestor = out.absolute()
    while not ancestor.exists():
        ancestor = ancestor.parent
    _check_writable_directory(out, ancestor)


def demo(out) -> None:
    """The demo job (the command line reaches it through here, never importing the demo)."""
    from .demo import run_demo
    run_demo(Path(out))


def _progress(message: str) -> None:
    print(f"[diagnose] {message}", file=sys.stderr, flush=True)


DIAGNOSIS_FILES = ("findings.json", "params.json", "params.ssv", "report.html")


def diagnose_to_directory(recording, params, out, validate=(), time_unit: str | None = None) -> dict:
    """Diagnose RECORDING (a path, or a list of paths of one joint, fitted
    jointly) against PARAMS (a JSON path, or None for the defaults; its
    "tolerance" object overrides the calibration priors) and write findings.json, params.json, params.ssv and
    report.html into OUT. Returns the findings document. Raises UserError
    for bad input; nothing is written unless everything was computed."""
    import json
    import tempfile
    from . import parameters, report
    from .diagnosis import DiagnosisError, diagnose
    from .validation import validate as validate_on
    paths = [recording] if isinstance(recording, (str, Path)) else list(recording)
    check_output_directory(out, DIAGNOSIS_FILES, inputs=(*paths, params, *validate))  # before any work
    recs = [read_recording(path, time_unit) for path in paths]
    others = [read_recording(path, time_unit) for path in validate]  # read first: a bad file stops before any work
    nominal = read_params(params)
    try:
        tolerance = parameters.load_tolerances(params)
    except parameters.ParameterError as e:
        raise UserError(str(e)) from None
    try:
        result, doc = diagnose(recs if len(recs) > 1 else recs[0], nominal, progress=_progress, tolerance=tolerance)
        if others:
            _progress("checking the corrected model on the other recordings")
            doc["validation"] = [validate_on(o, result.nominal, result.calibrated_params, doc["params"],
                                             fitted_on=result.engine.prep) for o in others]
    except DiagnosisError as e:
        raise UserError(str(e)) from None
    page = report.build(result, doc)
    # Everything is computed; stage the files, then move them in, so a
    # failure never leaves a half-written OUT.
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    with tempfile.TemporaryDirectory(dir=out) as tmp:
        stage = Path(tmp)
        (stage / "findings.json").write_text(json.dumps(doc, indent=2, default=float) + "\n")
        parameters.save(stage / "params.json", doc["params"])
        parameters.save_ssv(stage / "params.ssv", doc["params"], name="hdjoint corrected")
        (stage / "report.html").write_text(page)
        for name in DIAGNOSIS_FILES:
            os.replace(stage / name, out / name)  # never into a directory of that name
    return doc
