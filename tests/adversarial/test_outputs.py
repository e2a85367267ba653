"""Attacks through the output path (issue 56): a symbolic link where an
output goes (to a file, to stdout, dangling), one put there after the check,
an empty path. Each is refused with exit code 2 naming the path, and the
link and whatever it points to are left as they were."""
from __future__ import annotations

import os
import subprocess
import sys

import pytest

from hdjoint.io.outputs import OutputError, open_temp, replace_into

from cli_helpers import assert_one_line_error, rec_csv, run_cli, simulated  # noqa: F401 (fixtures)


def _link(tmp_path, kind):
    """A symbolic link out.csv and what it points to (None: nothing there)."""
    target = {"to a file": tmp_path / "victim.txt", "dangling": tmp_path / "nowhere.txt",
              "to a read-only file": tmp_path / "ro.txt"}[kind]
    if kind != "dangling":
        target.write_text("precious\n")
    if kind == "to a read-only file":
        target.chmod(0o444)
    link = tmp_path / "out.csv"
    link.symlink_to(target)
    return link, target


@pytest.mark.parametrize("kind", ["to a file", "dangling", "to a read-only file"])
@pytest.mark.parametrize("command", ["estimate", "simulate"])
def test_an_output_that_is_a_link_is_refused(rec_csv, tmp_path, capsys, kind, command):
    link, target = _link(tmp_path, kind)
    argv = ("estimate", rec_csv, "-o", link) if command == "estimate" else ("simulate", "--duration", "0.1",
                                                                            "-o", link)
    code, _, err = run_cli(capsys, *argv)
    assert code == 2
    assert_one_line_error(err, str(link), "symbolic link")
    assert link.is_symlink() and os.readlink(link) == str(target)
    assert (target.read_text() == "precious\n") if kind != "dangling" else not target.exists()
    assert not [p for p in os.listdir(tmp_path) if p.endswith(".tmp")]


def test_a_link_to_stdout_is_not_replaced(rec_csv, tmp_path):
    """The audit's case: `-o so_link` with so_link -> /proc/self/fd/1, stdout a regular file."""
    link = tmp_path / "so_link"
    link.symlink_to("/proc/self/fd/1")
    with open(tmp_path / "stdout.txt", "w") as stdout:
        done = subprocess.run([sys.executable, "-m", "hdjoint.app.cli", "estimate", str(rec_csv), "-o", str(link)],
                              stdout=stdout, stderr=subprocess.PIPE, text=True, cwd=tmp_path, timeout=120)
    assert done.returncode == 2, done.stderr
    assert "symbolic link" in done.stderr and str(link) in done.stderr
    assert link.is_symlink()


def test_a_link_in_the_diagnosis_folder_is_refused(rec_csv, tmp_path, capsys):
    out = tmp_path / "d"
    out.mkdir()
    victim = tmp_path / "victim.json"
    victim.write_text("{}\n")
    (out / "params.json").symlink_to(victim)
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--out", out)
    assert code == 2
    assert_one_line_error(err, str(out / "params.json"), "symbolic link")
    assert victim.read_text() == "{}\n" and (out / "params.json").is_symlink()


@pytest.mark.parametrize("placed", ["a link", "a FIFO", "a read-only file"])
def test_what_appears_after_the_check_is_not_replaced(tmp_path, placed):
    """Between the check and the move, something else is put where the output goes: the move refuses it."""
    target = tmp_path / "out.csv"
    f, tmp = open_temp(target)
    with f:
        f.write("new\n")
    if placed == "a link":
        (tmp_path / "victim").write_text("precious\n")
        target.symlink_to(tmp_path / "victim")
    elif placed == "a FIFO":
        os.mkfifo(target)
    else:
        target.write_text("precious\n")
        target.chmod(0o444)
    with pytest.raises(OutputError, match="out.csv"):
        replace_into(tmp, target)
    if placed == "a link":
        assert target.is_symlink() and (tmp_path / "victim").read_text() == "precious\n"
    elif placed == "a read-only file":
        assert target.read_text() == "precious\n"
    os.unlink(tmp)


@pytest.mark.parametrize("existing", [False, True])
def test_a_regular_output_is_still_replaced_with_its_mode(tmp_path, existing):
    target = tmp_path / "out.csv"
    if existing:
        target.write_text("old\n")
        target.chmod(0o640)
    f, tmp = open_temp(target)
    with f:
        f.write("new\n")
    replace_into(tmp, target)
    assert target.read_text() == "new\n" and not os.path.exists(tmp)
    if existing:
        assert target.stat().st_mode & 0o777 == 0o640


def test_the_temporary_file_is_never_opened_through_a_link(tmp_path, monkeypatch):
    """A link planted under the temporary file's name is not followed (O_EXCL, O_NOFOLLOW)."""
    victim = tmp_path / "victim"
    victim.write_text("precious\n")
    planted = tmp_path / ".out.csv.planted.tmp"
    planted.symlink_to(victim)
    monkeypatch.setattr("hdjoint.io.outputs.temp_path", lambda path: str(planted))
    with pytest.raises(FileExistsError):
        open_temp(tmp_path / "out.csv")
    assert victim.read_text() == "precious\n"


@pytest.mark.parametrize("argv", [("diagnose", "{rec}", "--out", ""), ("estimate", "{rec}", "-o", ""),
                                  ("simulate", "-o", ""), ("fmus", "--out", ""), ("demo", "--out", ""),
                                  ("fleet", "estimate", "{rec}", "--out", ""), ("fleet", "generate", "")],
                         ids=lambda a: " ".join(a[:2]))
def test_an_empty_output_path_is_refused(rec_csv, tmp_path, capsys, monkeypatch, argv):
    monkeypatch.chdir(tmp_path)
    before = sorted(os.listdir(tmp_path))
    code, _, err = run_cli(capsys, *(a.format(rec=rec_csv) for a in argv))
    assert code == 2
    assert_one_line_error(err, "empty")
    assert sorted(os.listdir(tmp_path)) == before


# ---------------------------------------------------------------- folders: fmus, demo, fleet generate

FOLDER_COMMANDS = [("fmus", "--out", "{out}"), ("demo", "--out", "{out}"),
                   ("fleet", "generate", "{out}", "--joints", "1", "--days", "1", "--duration", "0.5")]


@pytest.mark.parametrize("argv", FOLDER_COMMANDS, ids=lambda a: " ".join(a[:2]))
def test_a_folder_that_cannot_be_made_is_refused_before_any_work(tmp_path, capsys, argv):
    blocker = tmp_path / "a-file"
    blocker.write_text("x\n")
    out = blocker / "out"
    code, _, err = run_cli(capsys, *(a.format(out=out) for a in argv))
    assert code == 2
    assert_one_line_error(err, str(out), "not a directory")
    assert "Errno" not in err
    assert sorted(os.listdir(tmp_path)) == ["a-file"]


def _disk_full(*args, **kwargs):
    raise OSError(28, "No space left on device")


@pytest.mark.parametrize("argv", FOLDER_COMMANDS, ids=lambda a: " ".join(a[:2]))
def test_a_full_disk_leaves_no_folder(tmp_path, capsys, monkeypatch, argv):
    """The disk fills while the folder is written: exit 2 naming the file, and no half-written (or empty) folder."""
    import shutil
    from hdjoint.io import recording
    if argv[0] == "fleet":  # the recordings
        monkeypatch.setattr(recording.CsvWriter, "write_cells", lambda self, cells: self._guard(_disk_full))
    else:  # the FMUs (fmus, demo's first step)
        monkeypatch.setattr(shutil, "copyfileobj", _disk_full)
    out = tmp_path / "new" / "out"
    code, _, err = run_cli(capsys, *(a.format(out=out) for a in argv))
    assert code == 2
    told = [line for line in err.splitlines() if line.startswith("hdjoint ")]  # after the demo's progress lines
    assert len(told) == 1
    assert_one_line_error(told[0], str(out), "the disk is full")
    assert "Errno" not in err
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------------------- a full temporary folder

def _can_mount_privately() -> bool:
    import shutil
    if not shutil.which("unshare"):
        return False
    return subprocess.run(["unshare", "-rm", "true"], capture_output=True).returncode == 0


@pytest.mark.skipif(not _can_mount_privately(), reason="needs unshare -rm (a private mount namespace)")
@pytest.mark.parametrize("engine", ["batch", "fmu"])
def test_a_full_temporary_folder_is_told_plainly(simulated, tmp_path, engine):
    """--smooth (or the FMU's unpacking) with TMPDIR on a 256 kB file system of its own (in a private mount
    namespace: nothing outside sees it): exit 2, the folder named as full, nothing left."""
    small = tmp_path / "small"
    small.mkdir()
    out = tmp_path / "s.csv"
    script = (f"mount -t tmpfs -o size=256k tmpfs {small} && TMPDIR={small} {sys.executable} -m hdjoint.app.cli "
              f"estimate {simulated} --smooth --engine {engine} -o {out}; code=$?; ls -A {small}; exit $code")
    done = subprocess.run(["unshare", "-rm", "sh", "-c", script], capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    assert_one_line_error(done.stderr, str(small), "full")
    assert "requested and" not in done.stderr
    assert done.stdout == ""  # the small folder is left empty
    assert not out.exists() and sorted(os.listdir(tmp_path)) == ["small"]


@pytest.mark.parametrize("writer", ["text", "figure", "parameters"])
def test_every_whole_file_writer_refuses_a_link(tmp_path, writer):
    """The files fleet generate, demo and diagnose write whole (pages, maps, figures, parameter sets)."""
    from hdjoint.io import figures, parameters
    from hdjoint.io.outputs import write_whole
    victim = tmp_path / "victim"
    victim.write_text("precious\n")
    link = tmp_path / {"text": "truth.json", "figure": "torque.png", "parameters": "params.json"}[writer]
    link.symlink_to(victim)
    with pytest.raises(OutputError, match="symbolic link"):
        if writer == "text":
            write_whole(link, "{}\n")
        elif writer == "figure":
            import matplotlib
            matplotlib.use("Agg")
            import matplotlib.pyplot as plt
            figures.save(plt.figure(), link)
        else:
            parameters.save(link, parameters.defaults())
    assert victim.read_text() == "precious\n" and link.is_symlink()
    assert sorted(os.listdir(tmp_path)) == sorted(["victim", link.name])


@pytest.mark.parametrize("planted", ["a link", "a FIFO"])
def test_a_lock_file_that_is_not_one_is_refused(rec_csv, tmp_path, capsys, planted):
    """The lock's name is known (.NAME.lock): a link planted there is neither followed nor truncated."""
    victim = tmp_path / "victim"
    victim.write_text("precious\n")
    lock = tmp_path / ".e.csv.lock"
    if planted == "a link":
        lock.symlink_to(victim)
    else:
        os.mkfifo(lock)
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", tmp_path / "e.csv")
    assert code == 2
    assert_one_line_error(err, str(tmp_path / "e.csv"), "cannot lock")
    assert victim.read_text() == "precious\n" and not (tmp_path / "e.csv").exists()
