"""A joint's parameter set calibrated from its ordinary recordings (encoders
and current; no torque sensor needed), for the estimators.

The diagnosis calibrates every nominal parameter and names what the model
lacks. Its corrected set, the maximum a posteriori with each parameter's
tolerance as its prior, goes to the estimator as fitted: the prior already
holds at its nominal value what the recordings do not see. A parameter they
do not identify alone (its interval wide) has moved with others along
combinations they do identify: without a sensor the spring's scale Kf, the
link's Jl and mgl and the motor's friction are each loosely known, their
balance well. Set back to its nominal value alone, it breaks that balance,
and the estimator's torque with it. Their common scale, which the recordings
cannot tell, is then set by all their tolerances together (joint_scale.py).
The encoder zero a0 is a property of each recording, so it is placed anew on
the recording to be estimated, against the motor's current-based torque."""
from __future__ import annotations

import json
import sys
import tempfile
from dataclasses import dataclass, replace
from pathlib import Path

from hdjoint.diagnosis import (Evaluator, channels_for, HELD_WITHOUT_SENSOR as HELD, kinematics, Prepared, diagnose,
                                DiagnosisError, check_recording, place_offset, INTERVAL)
from hdjoint.io import parameters
from hdjoint.io.outputs import check_replaceable, replace_into
from hdjoint.io.recording import Recording
from hdjoint.jobs.diagnose import screened_recordings
from hdjoint.jobs.calibration_spread import calibration_spread, widen_deviations
from hdjoint.jobs.inputs import UserError, check_output_file, read_params, read_recording
from hdjoint.jobs.joint_scale import (SCALE_EVIDENCE_Z, joint_scale, scale_interval, scaled, used_interval,
                                     torque_power)


@dataclass(frozen=True)
class CalibratedSet:
    params: dict          # the set the estimator runs with
    calibration: dict     # per parameter calibrated or scaled: nominal, estimate, interval, identified, the value used
                          # and, scaled, its interval (used_lo, used_hi: the estimate's and the scale's together)
    verdict: str          # the diagnosis's verdict on the calibration recordings
    findings: list[dict]  # what it named: effect, kind, parameters
    scale: float          # the joint's torque scale applied to the estimates (joint_scale.py)
    scale_interval: tuple[float, float] | None = None  # its interval at the diagnosis's coverage (None: a sensor
                                                       # set it)
    estimates: dict | None = None  # every parameter's estimate before the scale (the calibrated ones and the rest)
    correlation: dict | None = None  # the calibrated parameters' posterior correlations ({name: {other: r}})

    def document(self, recordings: list[str], jitter, spread=None) -> dict:
        """The calibration as written beside the estimates (`<output>.calibration.json`), with the
        reading-time JITTER the estimate ran with (a property of the estimated recording, not calibrated)
        and, with SPREAD (calibration_spread), what the calibrated parameters and the torque scale leave in
        tau_hat."""
        from hdjoint.jobs.estimate import READING_JITTER
        table = parameters.table()
        return {"calibrated_from": list(recordings), "verdict": self.verdict, "findings": self.findings,
                "rule": "every parameter at its estimate (maximum a posteriori, the tolerance its prior), "
                        "the torque-carrying ones times the joint's torque scale, the most probable under "
                        "every tolerance within its bounds and Kt's, an estimate pulling no harder beyond "
                        f"{SCALE_EVIDENCE_Z:g} tolerances; a0 is placed on the estimated recording; used_lo, used_hi: "
                        "a scaled value's interval, the estimate's and the scale's combined",
                "joint_scale": self.scale,
                "joint_scale_interval": list(self.scale_interval) if self.scale_interval else None,
                "parameters": {name: {"description": table[name].description, "unit": table[name].unit, **entry}
                               for name, entry in self.calibration.items()},
                "reading_time_jitter": {"parameter": READING_JITTER, "unit": "s", "used": jitter.std,
                                        "lo": jitter.lo, "hi": jitter.hi, "how": jitter.reason,
                                        "in_words": jitter.describe()},
                **({"tau_hat_deviation": {
                    "unit": "N.m", "how": "RMS over the estimated recording of tau_hat's deviation from the "
                    "calibrated parameters' intervals and correlations, and from the joint torque scale's "
                    "interval; tau_ukf_std, tau_hat_std and tau_smooth_std carry it beside the filters' own",
                    **{k: round(v, 6) for k, v in spread.shares.items()}}} if spread else {})}

    def describe_scale(self) -> str:
        """The joint's torque scale in words, for the summary: the one thing the recordings could not say."""
        if self.scale_interval is None:
            return f"{HELD} calibrated on the torque sensor: the joint's torque scale is measured"
        lo, hi = self.scale_interval
        kt = self.calibration[HELD]
        return (f"{HELD} {kt['used']:.4g} N.m/A: the joint's torque scale, {self.scale:.3f} x nominal "
                f"({100 * INTERVAL:g} % interval {lo:.3f}-{hi:.3f}), comes from the parameters' tolerances; "
                "recordings without a torque sensor cannot tell it")


def _progress(message: str) -> None:
    print(f"[calibrate] {message}", file=sys.stderr, flush=True)


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
    estimates = dict(doc["params"], **{name: entry["estimate"] for name, entry in doc["calibration"].items()})
    tolerance = statements.get("tolerance") or {}
    scale = joint_scale(doc["calibration"], nominal, tolerance)
    interval = scale_interval(doc["calibration"], nominal, tolerance)
    params = scaled(estimates, scale)
    table = {name: {k: entry[k] for k in ("nominal", "estimate", "lo", "hi", "identified") if k in entry}
             for name, entry in doc["calibration"].items()}
    for name in [*table, *(n for n in params if n not in table and params[n] != estimates[n])]:
        table.setdefault(name, {"nominal": nominal.get(name, estimates[name]), "estimate": estimates[name]})
        table[name]["used"] = params[name]
    if interval is not None:  # the held parameter is the scale: its interval is the scale's
        held = table.setdefault(HELD, {"nominal": estimates[HELD], "estimate": estimates[HELD], "used": params[HELD]})
        held.update(lo=estimates[HELD] * interval[0], hi=estimates[HELD] * interval[1], identified=False)
        for name, entry in table.items():  # a scaled value's interval takes in the scale's
            if name != HELD and torque_power(name) and entry.get("lo") is not None:
                entry["used_lo"], entry["used_hi"] = used_interval(
                    name, entry["estimate"], entry["lo"], entry["hi"], scale, interval)
    findings = [{"effect": f["effect"], "kind": f["kind"], "parameters": f.get("parameters", {})}
                for f in doc["findings"]]
    return CalibratedSet(params, table, doc["verdict"], findings, scale, interval, estimates,
                         doc.get("calibration_correlation", {}))


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


def estimate_calibrated(opts, calibrate_paths: list[str]):
    """Calibrate on CALIBRATE_PATHS (OPTS.params the nominal set), then
    estimate OPTS.recording with the calibrated set into OPTS.output; the set
    and its calibration are written beside it. Nothing is written unless
    everything was computed. The set leaves the reading-time jitter out unless
    OPTS.params sets it: each recording's own is measured. Returns the
    estimate's Estimated and the CalibratedSet."""
    from hdjoint.jobs.estimate import READING_JITTER, as_written, estimate_to_file
    params_file, document_file = sidecars(opts.output)
    check_output_file(opts.output, inputs=(opts.recording, opts.params, *calibrate_paths))
    for side in (params_file, document_file):
        check_output_file(side, inputs=(opts.recording, opts.params, *calibrate_paths))
    calibrated = calibrate_from(calibrate_paths, opts.params, opts.time_unit, opts.current_sign)
    run_rec = read_recording(opts.recording, opts.time_unit, opts.current_sign)
    run = placed_on(run_rec, calibrated.params)
    with tempfile.TemporaryDirectory(dir=Path(opts.output).absolute().parent) as tmp:
        stage = Path(tmp)
        parameters.save(stage / "params.json", as_written(run, opts.params))
        estimated = estimate_to_file(replace(opts, params=str(stage / "params.json"), output=str(stage / "estimates")))
        _progress("the calibration's share of the deviations: the set moved along its posterior's axes")
        spread = calibration_spread(run_rec, {**run, READING_JITTER: estimated.jitter.std}, calibrated.calibration,
                                    calibrated.correlation, calibrated.estimates, calibrated.scale,
                                    calibrated.scale_interval, lambda p: placed_on(run_rec, p))
        widen_deviations(str(stage / "estimates"), spread)
        document = calibrated.document(calibrate_paths, estimated.jitter, spread)
        (stage / "calibration.json").write_text(json.dumps(document, indent=2) + "\n")
        for staged, target in ((stage / "params.json", params_file), (stage / "calibration.json", document_file),
                               (stage / "estimates", Path(opts.output))):
            check_replaceable(target)
            replace_into(staged, target)
    return estimated, calibrated
