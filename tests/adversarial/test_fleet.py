"""Attacks on `hdjoint fleet` (issue 56): a worker count beyond what the
machine can run, refused before any cluster starts; recordings that are
links to files holding a secret, whose contents reach neither the messages
nor fleet.html, fleet.parquet or the stored rows."""
from __future__ import annotations

import shutil
import subprocess
import sys

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


MARKER = "S3CRET-MARKER-f1ee7"
SECRETS = {"evil.csv": f"root:{MARKER}:19000:0:99999:7:::\n",
           "cell.csv": f"time,i_m,theta_m,theta_l\n0,0,0,0\n0.001,{MARKER},0,0\n",
           "column.csv": f"time,i_m,theta_m,{MARKER}\n0,0,0,0\n"}


def test_a_linked_secret_reaches_no_fleet_output(simulated, tmp_path):
    import pyarrow.parquet as pq
    logs = tmp_path / "logs"
    logs.mkdir()
    shutil.copyfile(simulated, logs / "good.csv")
    for name, text in SECRETS.items():
        secret = tmp_path / f"secret-{name}.txt"
        secret.write_text(text)
        (logs / name).symlink_to(secret)
    out = tmp_path / "f"
    done = subprocess.run([sys.executable, "-m", "hdjoint.app.cli", "fleet", "estimate", str(logs / "*.csv"),
                           "--out", str(out), "--workers", "1", "--quiet", "--engine", "batch"],
                          capture_output=True, text=True, cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr
    assert MARKER not in done.stdout + done.stderr
    assert "3 failed" in done.stdout
    page = (out / "fleet.html").read_text()
    assert MARKER not in page and "evil.csv" in page and "line 1" in page
    cells = [str(v) for column in pq.read_table(out / "fleet.parquet").to_pylist() for v in column.values()]
    assert not [c for c in cells if MARKER in c]
    assert any("cell.csv" in c for c in cells) and any("not a number" in c for c in cells)
    for row in (out / ".fleet" / "rows").iterdir():
        assert MARKER not in row.read_text()
