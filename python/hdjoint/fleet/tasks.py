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


def estimate(job: Job, out: Path, engine: str) -> dict:
    """Torque estimates into out/estimates.csv through the single-recording
    job (one reading path: the same time-base checks, gaps and jitter refused,
    Ts checked against the parameter file); error figures against the sensor,
    and the encoders' reading-time jitter the filter ran with (s, with its
    interval: a logger that starts reading late shows in the fleet's table)."""
    from hdjoint.jobs.estimate import READING_JITTER, Options, estimate_to_file
    out.mkdir(parents=True, exist_ok=True)
    estimated = estimate_to_file(Options(recording=job.recording, output=str(out / "estimates.csv"),
                                         params=job.params, engine=engine))
    row = {}
    for name in ESTIMATES:
        if name in estimated.figures:
            row[f"est.{name}.rms"], row[f"est.{name}.max"] = estimated.figures[name].rms, estimated.figures[name].max
    jitter = estimated.jitter
    row[f"est.{READING_JITTER}"], row[f"est.{READING_JITTER}.lo"], row[f"est.{READING_JITTER}.hi"] = \
        jitter.std, jitter.lo, jitter.hi
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
