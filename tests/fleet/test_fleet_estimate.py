"""`hdjoint fleet estimate` on a real 2-worker LocalCluster: the same
numbers as the single-recording command, a planted bad file recorded as
failed, worker deaths retried (and bounded), and resumption after a kill."""
import json
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pyarrow.parquet as pq
import pytest

from hdjoint.app import cli
from hdjoint.fmu import experiments
from hdjoint.io import parameters
from hdjoint.fleet import store
from hdjoint.fleet.run import run_fleet
from hdjoint.estimation.metrics import error_figures
from hdjoint.io.recording import read_recording, write_recording

DURATION = 3.0


@pytest.fixture(scope="module")
def fleet(tmp_path_factory):
    root = tmp_path_factory.mktemp("fleet")
    for joint, day, seed in (("j1", "2026-01-01", 1), ("j1", "2026-01-02", 2), ("j2", "2026-01-01", 3)):
        path = root / "logs" / joint / f"{day}.csv"
        path.parent.mkdir(parents=True, exist_ok=True)
        write_recording(path, experiments.run("paper", duration=DURATION, sensors=experiments.Sensors(seed=seed)))
    (root / "logs" / "j2" / "2026-01-02.csv").write_text("time,i_m,theta_m,theta_l\n0.0,1.0,oops,0.0\n0.001,1.0,0.0,0.0\n")
    parameters.save(root / "nominal.json", dict(parameters.defaults(), Fc=0.02))
    (root / "map.json").write_text(json.dumps({"logs/j1/*.csv": "nominal.json", "logs/j2/*.csv": "nominal.json",
                                               "long/*.csv": "nominal.json"}))
    long = root / "long" / "long.csv"
    long.parent.mkdir()
    write_recording(long, experiments.run("paper", duration=30.0))
    return root


def _run(fleet, out, client, patterns=("logs/**/*.csv",), joint_pattern=r"logs/(?P<joint>j\d)/(?P<date>[\d-]+)\.csv"):
    return run_fleet("estimate", [str(fleet / p) for p in patterns], out, params_map=str(fleet / "map.json"),
                     joint_pattern=joint_pattern, client=client, options={"engine": "fmu"}, show_progress=False)


@pytest.mark.slow
def test_fleet_estimates_equal_the_single_recording_command(fleet, two_workers, tmp_path, capsys):
    out = tmp_path / "out"
    summary = _run(fleet, out, two_workers)
    assert summary.computed == 4 and summary.failed == 1
    table = pq.read_table(out / "fleet.parquet").to_pylist()
    assert sorted(r["recording"] for r in table) == sorted(str(p) for p in (fleet / "logs").rglob("*.csv"))
    failed = [r for r in table if r["status"] == "failed"]
    assert len(failed) == 1 and "2026-01-02.csv" in failed[0]["error"] and "theta_m" in failed[0]["error"]
    for row in (r for r in table if r["status"] == "ok"):
        reference = out / "ref.csv"
        assert cli.main(["estimate", row["recording"], "--params", str(fleet / "nominal.json"), "-o",
                         str(reference)]) == 0
        expected = np.genfromtxt(reference, delimiter=",", names=True)
        got = np.genfromtxt(out / row["outputs"] / "estimates.csv", delimiter=",", names=True)
        for name in ("tau_compliance", "tau_ukf", "tau_hat"):
            np.testing.assert_array_equal(got[name], expected[name])
            sensor = read_recording(row["recording"]).tau_sensor
            assert row[f"est.{name}.rms"] == pytest.approx(error_figures(expected[name], sensor).rms, rel=1e-12)
    capsys.readouterr()


def test_a_rerun_reuses_every_finished_result(fleet, two_workers, tmp_path):
    out = tmp_path / "out"
    first = _run(fleet, out, two_workers)
    stamps = {p: p.stat().st_mtime_ns for p in (out / store.ROWS).glob("*.json")}
    assert len(stamps) == 4  # the failure of a malformed file is stored too: the same bytes fail the same way
    again = _run(fleet, out, two_workers)
    assert (again.computed, again.cached) == (0, 4)
    assert {p: p.stat().st_mtime_ns for p in (out / store.ROWS).glob("*.json")} == stamps
    assert [r["key"] for r in again.rows] == [r["key"] for r in first.rows]


@pytest.mark.slow
def test_a_killed_run_restarts_where_it_stopped(fleet, two_workers, tmp_path):
    out = tmp_path / "out"
    rows_dir = out / store.ROWS
    command = [sys.executable, "-m", "hdjoint.app.cli", "fleet", "estimate", str(fleet / "logs/**/*.csv"),
               str(fleet / "long/*.csv"), "--params-map", str(fleet / "map.json"), "--out", str(out),
               "--workers", "1", "--quiet"]
    run = subprocess.Popen(command, start_new_session=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    deadline = time.monotonic() + 120
    while not list(rows_dir.glob("*.json")) and run.poll() is None and time.monotonic() < deadline:
        time.sleep(0.05)
    os.killpg(run.pid, signal.SIGKILL)  # the client, its cluster and its worker, mid-run
    run.wait()
    before = {p: p.stat().st_mtime_ns for p in rows_dir.glob("*.json")}
    assert 1 <= len(before) < 5, run.stderr.read().decode()
    resumed = _run(fleet, out, two_workers, patterns=("logs/**/*.csv", "long/*.csv"), joint_pattern=None)
    assert (resumed.cached, resumed.computed) == (len(before), 5 - len(before))
    assert {p: p.stat().st_mtime_ns for p in before} == before
    assert len(list(rows_dir.glob("*.json"))) == 5
    assert pq.read_table(out / "fleet.parquet").num_rows == 5


def _worker_running(client, key_prefix):
    for addr, keys in client.processing().items():
        if any(str(k).startswith(key_prefix) for k in keys):
            return addr
    return None


def _kill_worker_running(client, key_prefix, times):
    """SIGKILL the worker process running the task named key_prefix..., `times` times over."""
    killed = 0
    deadline = time.monotonic() + 120
    while killed < times and time.monotonic() < deadline:
        addr = _worker_running(client, key_prefix)
        if addr is None:
            time.sleep(0.01)
            continue
        try:
            pid = client.run(os.getpid, workers=[addr])[addr]
        except Exception:  # the worker went away between the two calls: look again
            continue
        os.kill(pid, signal.SIGKILL)
        killed += 1
        while _worker_running(client, key_prefix) == addr and time.monotonic() < deadline:
            time.sleep(0.01)  # until the scheduler has seen that worker die
    return killed


def _run_while_killing(fleet, client, out, times):
    result = {}
    thread = threading.Thread(target=lambda: result.update(
        summary=_run(fleet, out, client, patterns=("long/*.csv",), joint_pattern=None)))
    thread.start()
    killed = _kill_worker_running(client, "estimate-", times)
    thread.join(timeout=300)
    return killed, result["summary"]


@pytest.mark.slow
def test_a_worker_killed_mid_run_is_retried(fleet, two_workers, tmp_path):
    killed, summary = _run_while_killing(fleet, two_workers, tmp_path / "out", times=1)
    assert killed == 1
    assert [r["status"] for r in summary.rows] == ["ok"], summary.rows


@pytest.mark.slow
def test_a_recording_that_keeps_killing_its_worker_is_marked_failed(fleet, two_workers, tmp_path):
    out = tmp_path / "out"
    killed, summary = _run_while_killing(fleet, two_workers, out, times=2)
    assert killed == 2
    (row,) = summary.rows
    assert row["status"] == "failed" and "KilledWorker" in row["error"]
    assert not list((out / store.ROWS).glob("*.json"))  # not stored: a rerun tries again
