"""Helpers of the command-line tests (tests/unit/test_cli*.py)."""
from __future__ import annotations

import csv

import numpy as np

from hdjoint.cli import main


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
