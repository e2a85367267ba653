"""Attacks through the inputs (issue 56): lines with no end (a /dev/zero, an
89 MB header), oversized parameter files and params maps, read under a
memory cap: refused at once with exit code 2 naming the file (and line),
never a MemoryError. A sample of 1e308 is refused naming file, line and
column, by either engine, before any arithmetic overflows."""
from __future__ import annotations

import resource
import subprocess
import sys
import warnings

import pytest

from hdjoint.io.recording import MAX_LINE, MAX_MAGNITUDE

from cli_helpers import assert_one_line_error, rec_csv, run_cli, simulated  # noqa: F401 (fixtures)

MEMORY_CAP = 1 << 30  # address space, bytes: ample for a run, far below what reading the files whole would take
HUGE = 700 << 20  # bytes of the endless line, a sparse file (no disk): NULs, as /dev/zero gives


def _cap():
    resource.setrlimit(resource.RLIMIT_AS, (MEMORY_CAP, MEMORY_CAP))


def _huge(path, start: str):
    with open(path, "w") as f:
        f.write(start)
        f.truncate(HUGE)
    return path


CASES = {  # name: (file's start, its role, the line named)
    "a header without end": ("time,i_m,theta_m,theta_l,", "recording", "line 1"),
    "a file of NULs": ("", "recording", "line 1"),
    "a row without end": ("time,i_m,theta_m,theta_l\n0,0,0,0\n0.001,", "recording", "line 3"),
    "a parameter file": ('{"Kt": ', "params", "1024 kB"),
    "a params map": ('{"*.csv": ', "map", "1024 kB"),
}


# A params map is read by fleet only; fleet reads the recordings on its workers (test_fleet.py).
PAIRS = [(case, command) for case, (_, role, _) in CASES.items() for command in ("estimate", "diagnose", "fleet")
         if (role == "map") == (command == "fleet")]


@pytest.mark.parametrize("case,command", PAIRS)
def test_a_line_without_end_is_refused_under_a_memory_cap(rec_csv, tmp_path, case, command):
    start, role, where = CASES[case]
    huge = _huge(tmp_path / "huge.json", start)
    recording = huge if role == "recording" else rec_csv
    argv = {"estimate": ["estimate", recording, "-o", tmp_path / "e.csv"],
            "diagnose": ["diagnose", recording, "--out", tmp_path / "d"],
            "fleet": ["fleet", "estimate", recording, "--out", tmp_path / "f", "--workers", "1"]}[command]
    argv += {"params": ["--params", huge], "map": ["--params-map", huge]}.get(role, [])
    done = subprocess.run([sys.executable, "-m", "hdjoint.app.cli", *map(str, argv)], capture_output=True,
                          text=True, cwd=tmp_path, timeout=120, preexec_fn=_cap,
                          env={"PATH": "/usr/bin:/bin", "OPENBLAS_NUM_THREADS": "1", "HOME": str(tmp_path)})
    assert done.returncode == 2, done.stderr
    assert_one_line_error(done.stderr, str(huge), where)
    assert "MemoryError" not in done.stderr
    if role == "recording":
        assert f"longer than {MAX_LINE} characters" in done.stderr


@pytest.mark.parametrize("column", ["time", "i_m", "theta_m", "theta_l", "tau_sensor"])
@pytest.mark.parametrize("engine", ["fmu", "batch"])
@pytest.mark.parametrize("value", ["1e308", "-1e308", "1.1e300"])
def test_an_enormous_sample_is_refused_naming_its_line_and_column(rec_csv, tmp_path, capsys, column, engine,
                                                                  value):
    lines = rec_csv.read_text().splitlines()
    header = lines[0].split(",")
    row = lines[100].split(",")
    row[header.index(column)] = value
    lines[100] = ",".join(row)
    rec_csv.write_text("\n".join(lines) + "\n")
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)  # an overflow on the way would raise, not pass
        code, _, err = run_cli(capsys, "estimate", rec_csv, "--engine", engine, "-o", tmp_path / "e.csv")
    assert code == 2
    assert_one_line_error(err, str(rec_csv), "line 101", f"column {column}", f"{MAX_MAGNITUDE:g}")
    assert not (tmp_path / "e.csv").exists()

