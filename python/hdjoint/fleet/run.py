"""Running a fleet on dask.distributed: a LocalCluster (one single-threaded
worker process per core) unless a scheduler address is given; every
recording one task; finished results skipped by their content key; worker
deaths retried up to `allowed_failures` times by the scheduler, then the
recording is marked failed; fleet.parquet and fleet.html written at the end."""
from __future__ import annotations

import importlib.util
import os
import re
import sys
import time
from dataclasses import dataclass, field
from pathlib import Path

from hdjoint.fleet import rows, store, tasks
from hdjoint.fleet.inputs import Job, plan
from hdjoint.jobs.inputs import UserError, check_output_directory, locked_output

FLEET_FILES = ("fleet.parquet", "fleet.html")

# How often the scheduler may lose a worker while it runs one recording
# before that recording is marked failed (Dask's allowed-failures).
ALLOWED_FAILURES = 2


@dataclass
class Summary:
    rows: list[dict] = field(default_factory=list)
    cached: int = 0      # found done from an earlier run
    computed: int = 0    # done now
    failed: int = 0      # failed (now or before)
    parquet: Path | None = None
    html: Path | None = None


class Progress:
    """One line over the recordings: done / failed / remaining and an ETA."""

    def __init__(self, total: int, cached: int, stream=None, enabled: bool = True):
        # sys.stderr as it is now: a default bound at import kept the stream of whoever imported this
        # module first (a test's capture, closed after it: "I/O operation on closed file" on every later run).
        stream = sys.stderr if stream is None else stream
        self.total, self.cached, self.stream, self.enabled = total, cached, stream, enabled
        self.done = self.failed = 0
        self.start = time.monotonic()
        self.last_print = 0.0
        self.tty = getattr(stream, "isatty", lambda: False)()

    def line(self) -> str:
        finished = self.done + self.failed
        remaining = self.total - self.cached - finished
        elapsed = time.monotonic() - self.start
        eta = f"{elapsed / finished * remaining:.0f} s" if finished else "?"
        width = 24
        filled = int(width * (self.cached + finished) / max(self.total, 1))
        return (f"[fleet] [{'#' * filled}{'.' * (width - filled)}] {self.cached + self.done}/{self.total} done "
                f"({self.cached} earlier), {self.failed} failed, {remaining} remaining, ETA {eta}")

    def update(self, failed: bool, final: bool = False) -> None:
        if failed:
            self.failed += 1
        else:
            self.done += 1
        self.show(final)

    def show(self, final: bool = False) -> None:
        if not self.enabled:
            return
        now = time.monotonic()
        if self.tty:
            print("\r" + self.line(), end="\n" if final else "", file=self.stream, flush=True)
        elif final or now - self.last_print >= 2.0:
            print(self.line(), file=self.stream, flush=True)
            self.last_print = now


def has_dashboard() -> bool:
    return importlib.util.find_spec("bokeh") is not None


# A scheduler address: PROTOCOL://HOST:PORT, or HOST:PORT (tcp).
_ADDRESS = re.compile(r"\A(?:(?:tcp|tls|ucx|ws|wss)://)?(?:\[[0-9A-Fa-f:.]+\]|[A-Za-z0-9._-]+):\d{1,5}\Z")
CONNECT_TIMEOUT = "10s"


def check_scheduler(scheduler: str) -> None:
    """Refuse an address that cannot be a Dask scheduler's, before connecting."""
    if not _ADDRESS.match(scheduler):
        raise UserError(f"--scheduler {scheduler!r}: not a scheduler address (expected tcp://HOST:PORT or "
                        "tls://HOST:PORT)")


def connect(scheduler: str | None, workers: int | None, allowed_failures: int):
    """A Client: to the scheduler at ADDR, or to a new LocalCluster."""
    import dask
    from distributed import Client, LocalCluster
    if scheduler:
        check_scheduler(scheduler)
        # The scheduler's own configuration sets its allowed-failures there.
        try:
            return Client(scheduler, timeout=CONNECT_TIMEOUT)
        except Exception as e:  # noqa: BLE001 - a refused port, a timeout, or garbage read as a message length
            reason = str(e).splitlines()[0] if str(e) else type(e).__name__
            raise UserError(f"--scheduler {scheduler}: no Dask scheduler answered there ({reason[:200]})") from None
    with dask.config.set({"distributed.scheduler.allowed-failures": allowed_failures}):
        # ":0": any free port, so two fleets on one machine do not contend for 8787.
        cluster = LocalCluster(n_workers=workers or os.cpu_count() or 1, threads_per_worker=1, processes=True,
                               dashboard_address=":0")
    return Client(cluster)


def _failed_row(command: str, job: Job, key: str, error: str) -> dict:
    return {"recording": job.recording, "joint": job.joint, "date": job.date, "command": command, "key": key,
            "status": "failed", "error": error, "findings": []}


def compute(client, command: str, jobs: list[Job], keys: list[str], out: str, options: dict,
            progress: Progress) -> list[dict]:
    """Submit the jobs and collect their rows as they finish (only rows travel back)."""
    from distributed import as_completed
    futures = {}
    for job, key in zip(jobs, keys):
        f = client.submit(tasks.run_one, command, job, out, key, options, pure=False,
                          key=f"{command}-{job.joint}-{job.name}-{key[:10]}")
        futures[f] = (job, key)
    found = []
    for f in as_completed(list(futures)):
        job, key = futures.pop(f)
        try:
            row = f.result()
        except Exception as e:  # noqa: BLE001 (KilledWorker after allowed-failures deaths, or cancelled: not stored, retried next run)
            row = _failed_row(command, job, key, f"{type(e).__name__}: {e}")
        f.release()
        found.append(row)
        progress.update(row["status"] != "ok")
    return found


def run_fleet(command: str, patterns: list[str], out: str | os.PathLike, params_map: str | None = None,
              joint_pattern: str | None = None, scheduler: str | None = None, workers: int | None = None,
              options: dict | None = None, client=None, allowed_failures: int = ALLOWED_FAILURES,
              show_progress: bool = True, write_report: bool = True) -> Summary:
    """Process every recording matching PATTERNS; return the summary. Rows
    found under OUT from an earlier run (same contents, same command) are reused."""
    options = dict(options or {})
    check_output_directory(out, FLEET_FILES)  # empty, a file, an unwritable place: before any work
    out = str(Path(out).resolve())
    if scheduler:
        check_scheduler(scheduler)
    jobs = plan(patterns, params_map, joint_pattern, out=out)
    with locked_output(out):
        return _run_locked(command, jobs, out, scheduler, workers, options, client, allowed_failures,
                           show_progress, write_report)


def _run_locked(command, jobs, out, scheduler, workers, options, client, allowed_failures, show_progress,
                write_report) -> Summary:
    keys = [store.result_key(command, j.recording, j.params, options) for j in jobs]
    summary = Summary()
    todo = []
    for job, key in zip(jobs, keys):
        row = store.load_row(out, key)
        if row is None:
            todo.append((job, key))
        else:
            # The same contents may sit at another path or joint now: the row tells where it is today.
            row.update(recording=job.recording, joint=job.joint, date=job.date)
            summary.rows.append(row)
    summary.cached = len(summary.rows)
    progress = Progress(len(jobs), summary.cached, enabled=show_progress)
    if todo:
        own = client is None
        if own:
            client = connect(scheduler, workers, allowed_failures)
        try:
            if show_progress:
                n = len(client.scheduler_info().get("workers", {}))
                # A remote scheduler has its own dashboard (or none); a local one needs bokeh here.
                services = client.scheduler_info().get("services", {})
                link = client.dashboard_link if ("dashboard" in services if scheduler else has_dashboard()) else None
                print(f"[fleet] {len(todo)} to {command} on {n} workers ({summary.cached} done earlier)"
                      + (f"; dashboard {link}" if link else ""), file=sys.stderr, flush=True)
            new = compute(client, command, [j for j, _ in todo], [k for _, k in todo], out, options, progress)
        finally:
            if own:
                cluster = client.cluster
                client.close()
                if cluster is not None:
                    cluster.close()
        summary.rows += new
        summary.computed = len(new)
    progress.show(final=True)
    order = {j.recording: i for i, j in enumerate(jobs)}
    summary.rows.sort(key=lambda r: order.get(r["recording"], len(order)))
    summary.failed = sum(r.get("status") != "ok" for r in summary.rows)
    summary.parquet = write_parquet(out, summary.rows)
    if write_report:
        from hdjoint.fleet.report import write_report as write_html
        summary.html = write_html(out, summary.rows)
    return summary


def write_parquet(out: str, found: list[dict]) -> Path:
    import io

    import pyarrow.parquet as pq
    buf = io.BytesIO()
    pq.write_table(rows.table(found), buf)
    path = Path(out) / "fleet.parquet"
    store.atomic_write(path, buf.getvalue())
    return path
