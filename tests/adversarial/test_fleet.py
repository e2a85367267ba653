"""Attacks on `hdjoint fleet` (issue 56): a worker count beyond what the
machine can run, refused before any cluster starts."""
from __future__ import annotations

import pytest

from hdjoint.fleet.cli import WORKERS_PER_CORE, max_workers

from cli_helpers import assert_one_line_error, rec_csv, run_cli, simulated  # noqa: F401 (fixtures)


@pytest.mark.parametrize("workers", ["0", "-1", "100000", "past"])
def test_a_worker_count_beyond_the_bound_is_refused(rec_csv, tmp_path, capsys, workers):
    count = str(max_workers() + 1) if workers == "past" else workers
    code, _, err = run_cli(capsys, "fleet", "estimate", rec_csv, "--out", tmp_path / "f", "--workers", count)
    assert code == 2
    assert_one_line_error(err, f"--workers {count}", f"from 1 to {max_workers()}")
    assert not (tmp_path / "f").exists()


def test_the_bound_is_stated_per_core():
    assert max_workers() >= WORKERS_PER_CORE >= 1
