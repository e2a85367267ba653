"""Helpers of the command-line tests (tests/unit/test_cli*.py)."""
from __future__ import annotations

import csv
import shutil

import numpy as np
import pytest

from hdjoint.app.cli import main


def read_csv(path):
    """Header and float rows, read with the csv module (not hdjoint's reader)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    return rows[0], np.array(rows[1:], dtype=float)


def run_cli(capsys, *argv):
    code = main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return code, out, err


def assert_one_line_error(err, *fragments):
    text = err.strip()
    assert text, "nothing on stderr"
    assert "\n" not in text, f"more than one line on stderr:\n{err}"
    for fragment in fragments:
        assert fragment in text, f"{fragment!r} not in {text!r}"


def files_in(directory):
    return sorted(p.name for p in directory.iterdir())


def rewrite(path, edit):
    """Apply edit(header, rows) to a recording's text (rows are lists of cells)."""
    with open(path, newline="") as f:
        rows = list(csv.reader(f))
    header, body = edit(rows[0], rows[1:])
    with open(path, "w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(body)
    return path


# Fixtures, imported by the test modules that use them (a conftest.py in
# tests/unit would shadow the root one's module name `conftest`).
@pytest.fixture(scope="session")
def simulated(tmp_path_factory):
    """`hdjoint simulate --duration 2 -o rec.csv`, once per session."""
    d = tmp_path_factory.mktemp("sim")
    path = d / "rec.csv"
    assert main(["simulate", "--duration", "2", "-o", str(path)]) == 0
    return path


@pytest.fixture
def rec_csv(simulated, tmp_path):
    path = tmp_path / "rec.csv"
    shutil.copyfile(simulated, path)
    return path
