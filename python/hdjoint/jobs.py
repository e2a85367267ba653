"""Whole jobs from files to files, shared by the command line and the demo
(which call these, never each other): reading the user's inputs with errors
that name the file, and one diagnosis written into its directory."""
from __future__ import annotations

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


def read_recording(path):
    from .recording import RecordingError, read_recording as read
    try:
        return read(path)
    except RecordingError as e:
        raise UserError(str(e)) from None


def _progress(message: str) -> None:
    print(f"[diagnose] {message}", file=sys.stderr, flush=True)


def diagnose_to_directory(recording, params, out, validate=()) -> dict:
    """Diagnose RECORDING (a path, or a list of paths of one joint, fitted
    jointly) against PARAMS (a JSON path, or None for the defaults; its
    "tolerance" object overrides the calibration priors) and write findings.json, params.json, params.ssv and
    report.html into OUT. Returns the findings document. Raises UserError
    for bad input; nothing is written unless everything was computed."""
    import json
    import shutil
    import tempfile
    from . import parameters, report
    from .diagnosis import DiagnosisError, diagnose
    from .validation import validate as validate_on
    paths = [recording] if isinstance(recording, (str, Path)) else list(recording)
    recs = [read_recording(path) for path in paths]
    others = [read_recording(path) for path in validate]  # read first: a bad file stops before any work
    nominal = read_params(params)
    try:
        tolerance = parameters.load_tolerances(params)
    except parameters.ParameterError as e:
        raise UserError(str(e)) from None
    try:
        result, doc = diagnose(recs if len(recs) > 1 else recs[0], nominal, progress=_progress, tolerance=tolerance)
        if others:
            _progress("checking the corrected model on the other recordings")
            doc["validation"] = [validate_on(o, result.nominal, result.calibrated_params, doc["params"])
                                 for o in others]
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
        for name in ("findings.json", "params.json", "params.ssv", "report.html"):
            shutil.move(str(stage / name), out / name)
    return doc
