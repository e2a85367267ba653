"""One diagnosis from files to files: recordings and a parameter file in,
findings.json, params.json, params.ssv and report.html out, all or nothing."""
from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from hdjoint.io.outputs import (OutputError, check_replaceable, created_directory, printable, replace_into,
    sweep_debris, temp_path, write_error)
from hdjoint.jobs.inputs import UserError, check_output_directory, locked_output, read_params, read_recording


def _progress(message: str) -> None:
    print(f"[diagnose] {message}", file=sys.stderr, flush=True)


DIAGNOSIS_FILES = ("findings.json", "params.json", "params.ssv", "report.html")


def diagnose_to_directory(recording, params, out, validate=(), time_unit: str | None = None,
                          current_sign: float = 1.0) -> dict:
    """Diagnose RECORDING (a path, or a list of paths of one joint, fitted
    jointly) against PARAMS (a JSON path, or None for the defaults; its
    "tolerance" object overrides the calibration priors, its "accuracy" and
    "sensor_noise" set the verdict's yardstick) and write findings.json, params.json, params.ssv and
    report.html into OUT. Returns the findings document. Raises UserError
    for bad input; nothing is written unless everything was computed."""
    paths = [recording] if isinstance(recording, (str, Path)) else list(recording)
    check_output_directory(out, DIAGNOSIS_FILES, inputs=(*paths, params, *validate))  # before any work
    with locked_output(out):
        return _diagnose_locked(paths, params, out, validate, time_unit, current_sign)


def _diagnose_locked(paths, params, out, validate, time_unit, current_sign) -> dict:
    from hdjoint.diagnosis import helper, prepare_drawing
    # The report's figures are drawn by a helper that imports matplotlib while the diagnosis runs.
    with helper(prepare_drawing) as drawing:
        doc, page = _diagnosed(paths, params, validate, time_unit, current_sign, drawing)
    from hdjoint.jobs.estimate import as_written
    write_diagnosis(out, doc, page, as_written(doc["params"], params))
    return doc


def _diagnosed(paths, params, validate, time_unit, current_sign, drawing) -> tuple[dict, str]:
    from hdjoint.io import parameters
    from hdjoint.diagnosis import report, where, DiagnosisError, diagnose, validate as validate_on
    recs = [read_recording(path, time_unit, current_sign) for path in paths]
    # The other recordings are read first too: a bad file stops before any work.
    others = [read_recording(path, time_unit, current_sign) for path in validate]
    recs, screened = screened_recordings(recs)
    others, screened_others = screened_recordings(others)
    nominal = read_params(params)
    try:
        statements = parameters.load_statements(params)
    except parameters.ParameterError as e:
        raise UserError(str(e)) from None
    started = {}

    def draw_figures(objective, calibrated, corrected, findings):  # the figures drawn while the diagnosis ends
        segments = [s for f in findings for s in where(objective, f)["time_segments"]]
        started["figures"] = report.figures(objective, calibrated, corrected, segments, drawing)

    try:
        result, doc = diagnose(recs if len(recs) > 1 else recs[0], nominal, progress=_progress,
                               when_settled=draw_figures if drawing is not None else None, **statements)
        if others:
            _progress("checking the corrected model on the other recordings")
            doc["validation"] = [validate_on(o, result.nominal, result.calibrated_params, doc["params"],
                                             fitted_on=result.objective.prep) for o in others]
    except DiagnosisError as e:
        raise UserError(str(e)) from None
    except np.linalg.LinAlgError as e:  # a failure while running, named with the recording
        raise RuntimeError(f"{', '.join(map(str, paths))}: the diagnosis failed ({e})") from None
    doc["screening"] = ([dict(s.as_dict(), role="diagnosed") for s in screened]
                        + [dict(s.as_dict(), role="validation") for s in screened_others])
    return doc, report.build(result, doc, drawing, started.get("figures"))


def screened_recordings(recs):
    """Each recording with its outliers left out, and what was found; a
    degenerate one (a channel that never varies, a wrapping encoder) refused."""
    from hdjoint.io.screening import Degenerate, check_not_degenerate, screen
    cleaned, found = [], []
    for rec in recs:
        try:
            check_not_degenerate(rec)  # a wrapping encoder first: its jumps are no outliers
            rec, screening = screen(rec)
            check_not_degenerate(rec)  # a channel that only a wild sample made vary
        except Degenerate as e:
            raise UserError(str(e)) from None
        if screening.outliers or screening.kept_as_recorded:
            _progress(f"{printable(rec.path)}: {screening.summary()}")
        cleaned.append(rec)
        found.append(screening)
    return cleaned, found


def write_diagnosis(out, doc: dict, page: str, corrected: dict) -> None:
    """Stage the four files (CORRECTED the set params.json and .ssv hold) in
    a folder inside OUT, then move them in, so a failure (a full disk) never
    leaves a half-written OUT, nor an OUT this run created; a run killed
    outright leaves its staging folder, which the next run removes."""
    import json
    import shutil
    from hdjoint.io import parameters
    from hdjoint.io.screening import strict_json
    out = Path(out)
    created = created_directory(out)
    stage = None
    try:
        out.mkdir(parents=True, exist_ok=True)
        sweep_debris(out / "stage")
        stage = Path(temp_path(out / "stage"))
        stage.mkdir()
        findings = json.dumps(strict_json(doc), indent=2, allow_nan=False) + "\n"  # strict JSON: NaN is null
        for name, write in (("findings.json", lambda p: p.write_text(findings)),
                            ("params.json", lambda p: parameters.save(p, corrected)),
                            ("params.ssv", lambda p: parameters.save_ssv(p, corrected, name="hdjoint corrected")),
                            ("report.html", lambda p: p.write_text(page))):
            try:
                write(stage / name)
            except OSError as e:
                raise write_error(out / name, e) from None
            except OutputError as e:  # from parameters.save: it names the staged file
                raise OutputError(str(e).replace(str(stage / name), str(out / name))) from None
        for name in DIAGNOSIS_FILES:
            check_replaceable(out / name)  # again: it may have changed while we computed
        for name in DIAGNOSIS_FILES:
            replace_into(stage / name, out / name)  # never into a directory of that name; modes kept
    except OutputError as e:
        raise UserError(str(e)) from None
    except OSError as e:
        raise UserError(str(write_error(out, e))) from None
    finally:
        if stage is not None:
            shutil.rmtree(stage, ignore_errors=True)
        if created and created[0].exists() and not any(created[-1].iterdir()):
            for folder in reversed(created):
                try:
                    folder.rmdir()
                except OSError:
                    break
