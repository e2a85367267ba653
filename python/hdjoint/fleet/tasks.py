"""The work for one recording, run on a Dask worker: it writes the
recording's own outputs under DIR/<joint>/<name>/ and its row under
DIR/.fleet/rows/<key>.json, and hands back only that small row, so nothing
of the signals travels to the client."""
from __future__ import annotations

import contextlib
import io
import time
import traceback
from pathlib import Path

from hdjoint.jobs.inputs import UserError
from hdjoint.fleet import rows, store
from hdjoint.fleet.inputs import Job

COMMANDS = ("diagnose", "estimate")
ESTIMATES = ("tau_compliance", "tau_ukf", "tau_hat")  # compared with tau_sensor when there is one
# Failures that the same bytes would raise again: stored, so a rerun does not
# repeat them. Anything else (a crash, memory) is not stored: a rerun retries.
DETERMINISTIC = (UserError, ValueError, RuntimeError)


def output_dir(out: str, job: Job) -> Path:
    return Path(out) / job.folder / job.name


def _estimator_params(job: Job, rec) -> dict:
    """The estimator's parameter set; Ts from the recording unless the file sets it."""
    from hdjoint.io import parameters
    from hdjoint.jobs.inputs import read_params
    from hdjoint.io.timebase import given_ts, sample_period
    params = read_params(job.params)
    params["Ts"] = sample_period(rec.median_step, given_ts(job.params))
    return parameters.for_estimator(params)


def estimate(job: Job, out: Path, engine: str) -> dict:
    """Torque estimates into out/estimates.csv; error figures against the sensor."""
    from hdjoint.jobs.inputs import read_recording
    from hdjoint.estimation.metrics import error_figures
    from hdjoint.io.recording import write_csv
    rec = read_recording(job.recording)
    params = _estimator_params(job, rec)
    if engine == "fmu":
        from hdjoint.fmu.runner import run_estimator_fmu
        est = run_estimator_fmu(rec.time, rec.i_m, rec.theta_m, rec.theta_l, params)
    else:
        from hdjoint import _core
        est = _core.run_estimator(params, rec.time, rec.i_m, rec.theta_m, rec.theta_l)
    out.mkdir(parents=True, exist_ok=True)
    write_csv(out / "estimates.csv", {"time": rec.time, **{k: est[k] for k in ESTIMATES}})
    row = {}
    if rec.tau_sensor is not None:
        for name in ESTIMATES:
            fig = error_figures(est[name], rec.tau_sensor)
            row[f"est.{name}.rms"], row[f"est.{name}.max"] = fig.rms, fig.max
    return row


def diagnose(job: Job, out: Path) -> dict:
    from hdjoint.jobs.diagnose import diagnose_to_directory
    return rows.diagnosis_row(diagnose_to_directory(job.recording, job.params, out))


def run_one(command: str, job: Job, out: str, key: str, options: dict) -> dict:
    """Process one recording; never raises for a failure of the recording
    itself (the row says why). Called on a worker."""
    if command not in COMMANDS:
        raise ValueError(f"unknown fleet command '{command}'")
    target = output_dir(out, job)
    row = {"recording": job.recording, "joint": job.joint, "date": job.date, "command": command, "key": key,
           "outputs": str(target.relative_to(out))}
    start = time.perf_counter()
    store_it = True
    try:
        # The single-recording jobs narrate on stderr; on a worker that would
        # garble the client's progress bar.
        with contextlib.redirect_stderr(io.StringIO()):
            result = diagnose(job, target) if command == "diagnose" else estimate(job, target, options["engine"])
        row.update(status="ok", error=None, **result)
    except DETERMINISTIC as e:
        row.update(status="failed", error=f"{type(e).__name__}: {e}")
    except Exception as e:  # noqa: BLE001 - recorded with its reason, the fleet goes on
        row.update(status="failed", error=f"{type(e).__name__}: {e} ({traceback.format_exc(limit=2).splitlines()[-1]})")
        store_it = False
    row["seconds"] = round(time.perf_counter() - start, 3)
    if store_it:
        store.save_row(out, key, row)
    return row
