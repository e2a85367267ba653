"""What the fleet refuses or reports (issue 37, items 3, 6, 8): its own
outputs are never recordings; fleet estimate reads recordings through the
single-recording job, with the same time-base checks; a fleet where every
recording failed exits 1; a bad --out or --scheduler is refused before any
cluster starts; a params-map pattern used for nothing is named."""
from __future__ import annotations

import json
import re
import signal
import socket
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from hdjoint.fleet.inputs import plan
from hdjoint.fleet.tasks import run_one
from hdjoint.fmu import experiments
from hdjoint.io.recording import read_recording, write_recording

CLI = [sys.executable, "-m", "hdjoint.app.cli"]


@pytest.fixture(scope="module")
def recording(tmp_path_factory):
    path = tmp_path_factory.mktemp("rec") / "r.csv"
    write_recording(path, experiments.run("paper", duration=2.0))
    return path


def _one_line(err: str) -> str:
    lines = [line for line in err.splitlines() if line.strip()]
    assert len(lines) == 1, err
    return lines[0]


# ---------------------------------------------------------------- its own outputs


def test_the_fleet_never_takes_its_own_outputs_for_recordings(tmp_path, recording):
    logs = tmp_path / "logs" / "j1"
    logs.mkdir(parents=True)
    (logs / "a.csv").write_bytes(recording.read_bytes())
    out = tmp_path / "logs" / "FLEET"  # inside the recordings' glob
    (out / "j1" / "a").mkdir(parents=True)
    (out / "j1" / "a" / "estimates.csv").write_text("time,tau_hat\n0,0\n")
    jobs = plan([str(tmp_path / "logs/**/*.csv")], None, None, out=out)
    assert [j.recording for j in jobs] == [str((logs / "a.csv").resolve())]


def test_a_glob_that_matches_only_the_fleets_outputs_is_refused(tmp_path, capsys):
    out = tmp_path / "FLEET"
    (out / "j").mkdir(parents=True)
    (out / "j" / "estimates.csv").write_text("time\n0\n")
    from hdjoint.app import cli
    code = cli.main(["fleet", "estimate", str(tmp_path / "**/*.csv"), "--out", str(out)])
    assert code == 2 and "outside --out" in _one_line(capsys.readouterr().err)


# ---------------------------------------------------------------- one reading path


def _job(recording, params=None):
    from hdjoint.fleet.inputs import Job
    return Job(str(recording), str(params) if params else None, "j", "2026-01-01", recording.stem)


def test_fleet_estimate_refuses_a_gap_as_estimate_does(tmp_path, recording):
    rec = read_recording(recording)
    keep = np.ones(len(rec), bool)
    keep[500:1500] = False  # a 1 s gap
    gapped = tmp_path / "gap.csv"
    write_recording(gapped, rec.slice(0, None).__class__(
        time=rec.time[keep], i_m=rec.i_m[keep], theta_m=rec.theta_m[keep], theta_l=rec.theta_l[keep],
        tau_sensor=rec.tau_sensor[keep]))
    row = run_one("estimate", _job(gapped), str(tmp_path / "out"), "k1", {"engine": "batch"})
    assert row["status"] == "failed" and "a gap of 1.001 s" in row["error"] and "lines 501 to 502" in row["error"]
    single = subprocess.run([*CLI, "estimate", str(gapped), "-o", str(tmp_path / "e.csv")], check=False, capture_output=True,
                            text=True)
    assert single.returncode == 2 and _one_line(single.stderr).split(": ", 1)[1] in row["error"]


def test_fleet_estimate_refuses_a_ts_the_recording_does_not_have(tmp_path, recording):
    params = tmp_path / "p.json"
    params.write_text('{"Ts": 0.002}')
    row = run_one("estimate", _job(recording, params), str(tmp_path / "out"), "k2", {"engine": "batch"})
    assert row["status"] == "failed" and "Ts = 0.002 s" in row["error"]


def test_fleet_estimate_writes_what_estimate_writes(tmp_path, recording):
    row = run_one("estimate", _job(recording), str(tmp_path / "out"), "k3", {"engine": "batch"})
    assert row["status"] == "ok", row
    single = tmp_path / "single.csv"
    subprocess.run([*CLI, "estimate", str(recording), "--engine", "batch", "-o", str(single)], check=True,
                   capture_output=True)
    assert (tmp_path / "out" / row["outputs"] / "estimates.csv").read_bytes() == single.read_bytes()
    assert row["est.tau_hat.rms"] > 0


# ---------------------------------------------------------------- exit codes, before the cluster


def test_a_fleet_where_every_recording_failed_exits_1(tmp_path):
    bad = tmp_path / "logs" / "bad.csv"
    bad.parent.mkdir()
    bad.write_text("time,i_m,theta_m,theta_l\n0.0,1.0,oops,0.0\n0.001,1.0,0.0,0.0\n")
    argv = [*CLI, "fleet", "estimate", str(bad), "--workers", "1", "--quiet", "--out", str(tmp_path / "out")]
    for _ in range(2):  # computed, then found failed from the first run
        run = subprocess.run(argv, check=False, capture_output=True, text=True)
        assert run.returncode == 1, run.stderr
        assert "every recording failed" in run.stderr and "line 2, column theta_m: not a number" in run.stderr


def test_a_fleet_out_that_is_a_file_is_refused_before_the_cluster(tmp_path, recording, capsys):
    from hdjoint.app import cli
    out = tmp_path / "out"
    out.write_text("a file")
    start = time.monotonic()
    code = cli.main(["fleet", "estimate", str(recording), "--out", str(out)])
    err = capsys.readouterr().err
    assert code == 2 and "not a directory" in _one_line(err) and str(out) in err
    assert time.monotonic() - start < 5 and out.read_text() == "a file"


@pytest.mark.parametrize("address", ["not a url", "http://example.com/x", "tcp://host"])
def test_a_scheduler_address_that_cannot_be_one_is_refused(tmp_path, recording, capsys, address):
    from hdjoint.app import cli
    code = cli.main(["fleet", "estimate", str(recording), "--scheduler", address, "--out", str(tmp_path / "o")])
    assert code == 2 and "--scheduler" in _one_line(capsys.readouterr().err)
    assert not (tmp_path / "o").exists()


def test_a_scheduler_that_is_not_dask_is_refused_in_one_line(tmp_path, recording):
    server = socket.socket()
    server.bind(("127.0.0.1", 0))
    server.listen()
    port = server.getsockname()[1]

    def answer_like_a_web_server():
        while True:
            try:
                conn, _ = server.accept()
            except OSError:
                return
            conn.sendall(b"HTTP/1.1 400 Bad Request\r\nContent-Length: 0\r\n\r\n" * 64)
            time.sleep(0.5)
            conn.close()

    threading.Thread(target=answer_like_a_web_server, daemon=True).start()
    try:
        run = subprocess.run([*CLI, "fleet", "estimate", str(recording), "--scheduler", f"tcp://127.0.0.1:{port}",
                              "--quiet", "--out", str(tmp_path / "o")], check=False,
                              capture_output=True, text=True, timeout=120)
    finally:
        server.close()
    assert run.returncode == 2, run.stderr
    line = _one_line(run.stderr)
    assert f"--scheduler tcp://127.0.0.1:{port}" in line and "no Dask scheduler" in line
    assert not (tmp_path / "o").exists()


def test_a_params_map_pattern_used_for_nothing_is_named(tmp_path, recording, capsys):
    (tmp_path / "logs").mkdir()
    (tmp_path / "logs" / "a.csv").write_bytes(recording.read_bytes())
    (tmp_path / "p.json").write_text("{}")
    (tmp_path / "map.json").write_text(json.dumps({"logs/*.csv": "p.json", "log/*.csv": "p.json"}))
    plan([str(tmp_path / "logs/*.csv")], str(tmp_path / "map.json"), None)
    err = capsys.readouterr().err
    assert "'log/*.csv' is used for none of the recordings" in err and "'logs/*.csv'" not in err


# ---------------------------------------------------------------- fleet.html


def test_fleet_html_takes_any_joint_id_and_escapes_every_field(tmp_path):
    from hdjoint.fleet.report import write_report
    rng = np.random.default_rng(2)
    found = []
    for joint in ("$x^$", "$\\frac{a}{b}$ <b>"):
        for day in range(6):
            found.append({"joint": joint, "date": f"2026-01-0{day + 1}", "status": "ok", "recording": f"/r/{day}.csv",
                          "command": "<script>alert(1)</script>", "param.Fc": 0.02 * (1 + 0.08 * day),
                          "param.Kf": 5e4 * (1 + 0.01 * rng.standard_normal())})
    page = write_report(tmp_path, found).read_text()  # raised in mathtext before
    assert "<script>" not in page and "&lt;script&gt;" in page
    assert page.count("<img") == 2 and "&lt;b&gt;" in page


def test_a_second_fleet_on_the_same_out_is_refused_while_the_first_runs(tmp_path, recording):
    out = tmp_path / "out"
    argv = [*CLI, "fleet", "estimate", str(recording), "--workers", "1", "--quiet", "--out", str(out)]
    first = subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    lock = tmp_path / ".out.lock"
    end = time.monotonic() + 60
    def held():  # the holder writes its pid once it has the lock
        try:
            return lock.read_text().strip() == str(first.pid)
        except FileNotFoundError:
            return False
    while not held() and first.poll() is None and time.monotonic() < end:
        time.sleep(0.005)
    first.send_signal(signal.SIGSTOP)  # hold it while the second tries
    try:
        second = subprocess.run(argv, check=False, capture_output=True, text=True, timeout=60)
    finally:
        first.send_signal(signal.SIGCONT)
    assert second.returncode == 2 and "another hdjoint run" in _one_line(second.stderr)
    first.communicate(timeout=120)
    assert first.returncode == 0 and not lock.exists()


def test_fleet_html_states_its_ranking_rule(tmp_path):
    from hdjoint.fleet.report import build
    found = [{"joint": "j", "date": f"2026-01-0{d + 1}", "status": "ok", "recording": f"/r/{d}.csv",
              "command": "diagnose", "param.Fc": 0.02 * (1 + 0.01 * d)} for d in range(6)]
    assert "Ranking: drifting joints first, then each group by its p-value" in build(found)


def test_a_joint_not_drifting_says_which_part_of_the_rule_it_misses():
    """A joint whose Fc rose 28 % at p = 0.0002 was listed "drifting: no" beside another effect, with
    no reason: the change was below the 30 % its tolerance asks. The cell now says so; a joint whose
    change reaches its tolerance reads "yes"."""
    from hdjoint.fleet.report import build
    noise = [0.0, 0.3, -0.2, 0.1, -0.3, 0.2, 0.0, -0.1]
    def rows(joint, tol):
        return [{"joint": joint, "date": f"2026-01-{d + 1:02d}", "status": "ok", "recording": f"/{joint}/{d}.csv",
                 "command": "diagnose", "param.Fc": 0.015 * (1 + 0.04 * d + 0.002 * noise[d]),
                 "param.Fc.tol": tol} for d in range(8)]
    page = build(rows("below", 0.3 * 0.015) + rows("beyond", 0.1 * 0.015))
    cells = {joint: re.search(rf"<td>{joint}</td><td>[^<]*</td><td>([^<]*)</td>", page).group(1)
             for joint in ("below", "beyond")}
    assert cells["beyond"] == "yes"
    assert cells["below"] == "no: significant, but Fc changes +28 %, under the 30 % its tolerance asks"



def test_the_ranking_names_each_quantity_with_its_meaning_and_unit():
    """The ranking showed a bare symbol ("Fc") and a slope with no unit."""
    from hdjoint.fleet.report import build
    found = [{"joint": "j", "date": f"2026-01-0{d + 1}", "status": "ok", "recording": f"/r/{d}.csv",
              "command": "diagnose", "param.Fc": 0.015 * (1 + 0.05 * d + 0.001 * (-1) ** d)} for d in range(6)]
    page = build(found)
    assert "<td>Fc (motor-side Coulomb friction)</td>" in page
    assert re.search(r"<td>[0-9.e-]+ N\.m/day</td>", page)
