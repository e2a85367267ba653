"""One diagnosis from files to files: recordings and a parameter file in,
findings.json, params.json, params.ssv and report.html out, all or nothing."""
from __future__ import annotations

import os
import sys
from pathlib import Path

from hdjoint.jobs.inputs import UserError, check_output_directory, read_params, read_recording


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
    from hdjoint.io import parameters
    from hdjoint.diagnosis import report
    from hdjoint.diagnosis.prepare import DiagnosisError
    from hdjoint.diagnosis.pipeline import diagnose
    from hdjoint.diagnosis.validation import validate as validate_on
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
                                             fitted_on=result.objective.prep) for o in others]
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
