"""A joint's parameter set calibrated from its ordinary recordings (encoders
and current; no torque sensor needed), for the estimators.

The diagnosis calibrates every nominal parameter and names what the model
lacks. Its corrected set goes to the estimator with one rule: a calibrated
parameter the recordings do not identify (its posterior not narrower than
half its prior, `rules.IDENTIFIED_RATIO`) stays at its nominal value unless
its interval (`rules.INTERVAL`) excludes that value. Without a torque sensor
the spring's scale and the motor side trade off against each other along a
direction the data cannot see; a parameter moved along it is a guess, and
the nominal value is the better one. A nominal value the data rule out is
no better a guess: a link far heavier than its CAD can leave a posterior
still wide beside its prior that yet excludes the nominal value. The encoder zero a0 is a
property of each recording, so it is placed anew on the recording to be
estimated, against the motor's current-based torque."""
from __future__ import annotations

import json
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

from hdjoint.diagnosis.channels import Evaluator, channels_for
from hdjoint.diagnosis.kinematics import kinematics
from hdjoint.diagnosis.part_torques import Prepared
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.diagnosis.prepare import DiagnosisError, check_recording, place_offset
from hdjoint.io import parameters
from hdjoint.io.outputs import check_replaceable, replace_into
from hdjoint.io.recording import Recording
from hdjoint.jobs.diagnose import screened_recordings
from hdjoint.jobs.inputs import UserError, check_output_file, read_params, read_recording


@dataclass(frozen=True)
class CalibratedSet:
    params: dict          # the set the estimator runs with
    calibration: dict     # per calibrated parameter: nominal, estimate, interval, identified, and the value used
    verdict: str          # the diagnosis's verdict on the calibration recordings
    findings: list[dict]  # what it named: effect, kind, parameters

    def document(self, recordings: list[str]) -> dict:
        """The calibration as written beside the estimates (`<output>.calibration.json`)."""
        table = parameters.table()
        return {"calibrated_from": list(recordings), "verdict": self.verdict, "findings": self.findings,
                "rule": "a parameter the recordings do not identify (posterior std over prior std >= 0.5) "
                        "keeps its nominal value unless its interval excludes it; a0 is placed on the "
                        "estimated recording",
                "parameters": {name: {"description": table[name].description, "unit": table[name].unit, **entry}
                               for name, entry in self.calibration.items()}}


def _progress(message: str) -> None:
    print(f"[calibrate] {message}", file=sys.stderr, flush=True)


def chosen(entry: dict) -> float:
    """The value the estimator runs with, from a calibration entry (nominal,
    estimate, lo, hi, identified): the estimate where the recordings identify
    the parameter or their interval rules the nominal value out; else the nominal value."""
    ruled_out = "lo" in entry and not entry["lo"] <= entry["nominal"] <= entry["hi"]
    return entry["estimate"] if entry["identified"] or ruled_out else entry["nominal"]


def calibrate_from(paths: list[str], params_path: str | None, time_unit: str | None = None,
                   current_sign: float = 1.0) -> CalibratedSet:
    """Calibrate the joint of PARAMS_PATH (None: the defaults) on the recordings at PATHS
    (screened for wild samples and degenerate channels, as `hdjoint diagnose` screens them)."""
    recs, _ = screened_recordings([read_recording(path, time_unit, current_sign) for path in paths])
    nominal = read_params(params_path)
    try:
        statements = parameters.load_statements(params_path)
        _, doc = diagnose(recs if len(recs) > 1 else recs[0], nominal, progress=_progress, **statements)
    except (parameters.ParameterError, DiagnosisError) as e:
        raise UserError(str(e)) from None
    params = dict(doc["params"])
    table = {}
    for name, entry in doc["calibration"].items():
        used = chosen(entry)
        params[name] = used
        table[name] = {k: entry[k] for k in ("nominal", "estimate", "lo", "hi", "identified") if k in entry}
        table[name]["used"] = used
    findings = [{"effect": f["effect"], "kind": f["kind"], "parameters": f.get("parameters", {})}
                for f in doc["findings"]]
    return CalibratedSet(params, table, doc["verdict"], findings)


def placed_on(rec: Recording, params: dict) -> dict:
    """PARAMS with the encoder zero a0 placed on REC, against the motor's current-based torque."""
    try:
        check_recording(rec)
    except DiagnosisError as e:
        raise UserError(str(e)) from None
    evaluator = Evaluator(Prepared(rec, kinematics(rec), rec.time - rec.time[0]), channels_for(False))
    return place_offset(rec, params, evaluator.estimate("motor", params))


def sidecars(output: str) -> tuple[Path, Path]:
    """Where the calibrated set and its document go beside OUTPUT: est.csv -> est.params.json, est.calibration.json."""
    out = Path(output)
    return out.with_suffix(".params.json"), out.with_suffix(".calibration.json")


def estimate_calibrated(opts, calibrate_paths: list[str]) -> dict:
    """Calibrate on CALIBRATE_PATHS (OPTS.params the nominal set), then
    estimate OPTS.recording with the calibrated set into OPTS.output; the set
    and its calibration are written beside it. Nothing is written unless
    everything was computed. Returns the estimate's error figures."""
    from hdjoint.jobs.estimate import estimate_to_file
    params_file, document_file = sidecars(opts.output)
    check_output_file(opts.output, inputs=(opts.recording, opts.params, *calibrate_paths))
    for side in (params_file, document_file):
        check_output_file(side, inputs=(opts.recording, opts.params, *calibrate_paths))
    calibrated = calibrate_from(calibrate_paths, opts.params, opts.time_unit, opts.current_sign)
    run = placed_on(read_recording(opts.recording, opts.time_unit, opts.current_sign), calibrated.params)
    with tempfile.TemporaryDirectory(dir=Path(opts.output).absolute().parent) as tmp:
        stage = Path(tmp)
        parameters.save(stage / "params.json", run)
        (stage / "calibration.json").write_text(json.dumps(calibrated.document(calibrate_paths), indent=2) + "\n")
        figures = estimate_to_file(replace(opts, params=str(stage / "params.json"), output=str(stage / "estimates")))
        for staged, target in ((stage / "params.json", params_file), (stage / "calibration.json", document_file),
                               (stage / "estimates", Path(opts.output))):
            check_replaceable(target)
            replace_into(staged, target)
    return figures
