"""What happens to the user's files around an output (issue 37, items 1-3):
a device node or a FIFO is never replaced; a read-only file is refused and a
writable one keeps its mode; two runs on one output do not race; a run
stopped by SIGTERM or SIGINT leaves nothing behind and says so in one line; a
run killed outright (SIGKILL) leaves debris that the next run removes.
Real processes, real signals, real files."""
from __future__ import annotations

import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import pytest

from cli_helpers import assert_one_line_error, files_in, rec_csv, run_cli, simulated  # noqa: F401 (fixtures)

CLI = [sys.executable, "-m", "hdjoint.app.cli"]


@pytest.fixture(scope="module")
def long_csv(tmp_path_factory):
    """A 30 s recording: long enough that a run can be caught mid-way."""
    path = tmp_path_factory.mktemp("long") / "long.csv"
    subprocess.run([*CLI, "simulate", "--duration", "30", "-o", str(path)], check=True, capture_output=True)
    return path


def _wait_for(predicate, timeout=60.0, proc=None):
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        found = predicate()
        if found:
            return found
        if proc is not None and proc.poll() is not None:
            raise AssertionError(f"the run ended first (rc {proc.returncode}): {proc.stderr.read()}")
        time.sleep(0.002)
    raise AssertionError("timed out")


def _temp_files(directory: Path, name: str):
    return [p for p in directory.iterdir() if p.name.startswith(f".{name}.") and p.name.endswith(".tmp")]


def _size(path: Path) -> int:
    """Bytes in a file, or files in a folder; 0 once it is gone (the run may remove it any time)."""
    try:
        return len(list(path.iterdir())) if path.is_dir() else path.stat().st_size
    except FileNotFoundError:
        return 0


def _start(*argv, env=None):
    return subprocess.Popen([*CLI, *map(str, argv)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env=env)


def _signal_stopped(proc, sig):
    """Deliver SIG to a process held stopped (so it cannot finish first), then let it run."""
    proc.send_signal(signal.SIGSTOP)
    proc.send_signal(sig)
    proc.send_signal(signal.SIGCONT)
    out, err = proc.communicate(timeout=60)
    return proc.returncode, err


# ---------------------------------------------------------------- device nodes, FIFOs, read-only files


def _special(tmp_path, kind):
    path = tmp_path / f"{kind}.csv"
    if kind == "fifo":
        os.mkfifo(path)
    else:
        try:
            os.mknod(path, 0o666 | stat.S_IFCHR, os.makedev(1, 3))  # a second /dev/null
        except PermissionError:
            pytest.skip("mknod needs privileges here")
    return path


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_estimate_never_replaces_a_device_node_or_fifo(rec_csv, tmp_path, capsys, kind):
    out = _special(tmp_path, kind)
    before = os.stat(out)
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 2
    assert_one_line_error(err, str(out), "FIFO" if kind == "fifo" else "character device")
    after = os.stat(out)
    assert stat.S_IFMT(after.st_mode) == stat.S_IFMT(before.st_mode) and after.st_ino == before.st_ino
    assert not _temp_files(tmp_path, out.name)


@pytest.mark.parametrize("kind", ["fifo", "device"])
def test_diagnose_never_replaces_a_device_node_named_like_its_files(rec_csv, tmp_path, capsys, kind):
    target = tmp_path / "out"
    target.mkdir()
    node = _special(target, kind)
    node.rename(target / "findings.json")
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--out", target)
    assert code == 2
    assert_one_line_error(err, str(target / "findings.json"))
    assert not stat.S_ISREG(os.stat(target / "findings.json").st_mode)
    assert files_in(target) == ["findings.json"]


def test_simulate_never_replaces_a_fifo(tmp_path, capsys):
    out = _special(tmp_path, "fifo")
    code, _, err = run_cli(capsys, "simulate", "--duration", "0.1", "-o", out)
    assert code == 2 and stat.S_ISFIFO(os.stat(out).st_mode)
    assert_one_line_error(err, str(out), "FIFO")


def test_a_read_only_output_is_refused_and_left_alone(rec_csv, tmp_path, capsys):
    out = tmp_path / "est.csv"
    out.write_text("keep me\n")
    out.chmod(0o444)
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 2  # also as root, who could write it: the mode says not to
    assert_one_line_error(err, str(out), "read-only")
    assert out.read_text() == "keep me\n" and stat.S_IMODE(out.stat().st_mode) == 0o444


def test_a_replaced_output_keeps_its_mode(rec_csv, tmp_path, capsys):
    out = tmp_path / "est.csv"
    out.write_text("old\n")
    out.chmod(0o640)
    code, _, _ = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 0 and out.read_text().startswith("time,")
    assert stat.S_IMODE(out.stat().st_mode) == 0o640


def test_diagnose_refuses_a_read_only_file_in_its_folder(rec_csv, tmp_path, capsys):
    target = tmp_path / "out"
    target.mkdir()
    (target / "report.html").write_text("mine")
    (target / "report.html").chmod(0o444)
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--out", target)
    assert code == 2
    assert_one_line_error(err, str(target / "report.html"), "read-only")
    assert files_in(target) == ["report.html"]


# ---------------------------------------------------------------- two runs, one output


def test_a_second_run_on_the_same_output_is_refused_while_the_first_runs(long_csv, tmp_path):
    out = tmp_path / "est.csv"
    first = _start("estimate", long_csv, "-o", out)
    try:
        _wait_for(lambda: _temp_files(tmp_path, out.name), proc=first)
        first.send_signal(signal.SIGSTOP)  # hold it mid-run
        second = subprocess.run([*CLI, "estimate", str(long_csv), "-o", str(out)], capture_output=True, text=True)
        assert second.returncode == 2
        assert_one_line_error(second.stderr, str(out), "another hdjoint run", f"pid {first.pid}")
    finally:
        first.send_signal(signal.SIGCONT)
    first.communicate(timeout=60)
    assert first.returncode == 0 and out.read_text().startswith("time,")
    assert files_in(tmp_path) == ["est.csv"]  # the lock file went with the run


# ---------------------------------------------------------------- interrupted runs


@pytest.mark.parametrize("sig, code, word", [(signal.SIGTERM, 143, "terminated"), (signal.SIGINT, 130, "interrupted")])
def test_an_interrupted_estimate_leaves_nothing_and_says_so_in_one_line(long_csv, tmp_path, sig, code, word):
    out = tmp_path / "est.csv"
    proc = _start("estimate", long_csv, "-o", out)
    # Mid-run: rows are being written (a signal inside a constructor is another, narrower case).
    _wait_for(lambda: [p for p in _temp_files(tmp_path, out.name) if _size(p) > 65536], proc=proc)
    rc, err = _signal_stopped(proc, sig)
    assert rc == code, err
    assert "Traceback" not in err
    assert_one_line_error(err, "hdjoint estimate:", word)
    assert files_in(tmp_path) == []


def test_a_terminated_smoothing_run_leaves_nothing_in_tmpdir(long_csv, tmp_path):
    out, tmp = tmp_path / "est.csv", tmp_path / "tmp"
    tmp.mkdir()
    proc = _start("estimate", long_csv, "--smooth", "-o", out, env={**os.environ, "TMPDIR": str(tmp)})
    # Mid-run: the smoother's records are being written.
    _wait_for(lambda: [p for p in tmp.iterdir() if p.name.startswith("hdjoint-smooth-") and _size(p)], proc=proc)
    rc, err = _signal_stopped(proc, signal.SIGTERM)
    assert rc == 143 and "Traceback" not in err, err
    assert files_in(tmp) == [] and files_in(tmp_path) == ["tmp"]


def test_debris_of_a_killed_estimate_is_removed_by_the_next_run(long_csv, rec_csv, tmp_path):
    out, tmp = tmp_path / "est.csv", tmp_path / "tmp"
    tmp.mkdir()
    env = {**os.environ, "TMPDIR": str(tmp)}
    proc = _start("estimate", long_csv, "--smooth", "-o", out, env=env)
    ours = lambda: [p for p in tmp.iterdir() if p.name.startswith("hdjoint-")]  # noqa: E731
    _wait_for(lambda: _temp_files(tmp_path, out.name) and ours(), proc=proc)
    proc.send_signal(signal.SIGKILL)
    proc.communicate(timeout=60)
    assert _temp_files(tmp_path, out.name) and ours()  # SIGKILL cannot be caught ...
    again = subprocess.run([*CLI, "estimate", str(rec_csv), "--smooth", "-o", str(out)], env=env,
                           capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    assert files_in(tmp_path) == ["est.csv", "rec.csv", "tmp"]  # ... the next run clears what it left:
    # its folders (hdjoint-*); a stranger's file there is not ours to remove (Python's own writability
    # probe of TMPDIR, a random 8-letter name, is left behind when a kill lands inside it).
    assert [f for f in files_in(tmp) if f.startswith("hdjoint-")] == []


def test_a_terminated_diagnosis_leaves_no_output_folder(rec_csv, tmp_path):
    target = tmp_path / "out"
    proc = _start("diagnose", rec_csv, "--out", target)
    _wait_for(lambda: proc.stderr.readline().startswith("[diagnose]"), proc=proc)
    rc, err = _signal_stopped(proc, signal.SIGTERM)
    assert rc == 143 and "Traceback" not in err
    assert files_in(tmp_path) == ["rec.csv"]


def test_a_killed_diagnosis_staging_folder_is_removed_by_the_next_run(rec_csv, tmp_path, capsys):
    target = tmp_path / "out"
    target.mkdir()
    dead = subprocess.Popen(["true"])
    dead.wait()
    stale = target / f".stage.{dead.pid}.0123456789ab.tmp"  # what a run killed while moving its files in leaves
    stale.mkdir()
    (stale / "findings.json").write_text("{")
    run = subprocess.run([*CLI, "diagnose", str(rec_csv), "--out", str(target)], capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    assert "Traceback" not in run.stderr  # its forked workers, stopped with SIGTERM at the end, die quietly
    assert files_in(target) == ["findings.json", "params.json", "params.ssv", "report.html"]


def test_fmus_never_writes_into_a_fifo_named_like_an_fmu(tmp_path, capsys):
    os.mkfifo(tmp_path / "JointController.fmu")  # opening it to write would block for ever
    code, _, err = run_cli(capsys, "fmus", "--out", tmp_path)
    assert code == 2
    assert_one_line_error(err, "JointController.fmu", "FIFO")
    assert files_in(tmp_path) == ["JointController.fmu"]


def test_ctrl_c_during_a_diagnosis_prints_one_line_from_all_its_processes(long_csv, tmp_path):
    """Ctrl-C reaches the whole process group, the diagnosis's forked workers too."""
    target = tmp_path / "out"
    proc = subprocess.Popen([*CLI, "diagnose", str(long_csv), "--out", str(target)], stderr=subprocess.PIPE,
                            text=True, start_new_session=True)
    _wait_for(lambda: "testing" in proc.stderr.readline(), proc=proc)  # the workers are fitting
    time.sleep(0.5)
    os.killpg(proc.pid, signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130
    assert "Traceback" not in err and "ForkPoolWorker" not in err
    assert_one_line_error("\n".join(line for line in err.splitlines() if not line.startswith("[diagnose]")),
                          "hdjoint diagnose:", "interrupted")
    assert not target.exists()
