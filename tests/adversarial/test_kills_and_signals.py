"""Attacks by signal (issue 56): `hdjoint diagnose` killed outright
(SIGKILL) leaves no forked helper or piece behind holding its output's lock,
at whatever stage it is killed, so the next run on that output goes ahead."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest

from hdjoint.io.outputs import OutputLock

from cli_helpers import simulated  # noqa: F401 (fixture)


def children(pid: int) -> list[int]:
    found = []
    for entry in os.listdir("/proc"):
        if entry.isdigit():
            try:
                with open(f"/proc/{entry}/stat") as f:
                    fields = f.read().rsplit(")", 1)[1].split()
            except OSError:
                continue
            if int(fields[1]) == pid:
                found.append(int(entry))
    return found


def descendants(pid: int) -> list[int]:
    out = []
    for child in children(pid):
        out += [child] + descendants(child)
    return out


def alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except OSError:
        return False


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")
@pytest.mark.parametrize("after", [0.2, 1.5], ids=["while the helper prepares", "while the diagnosis fits"])
def test_no_orphan_survives_a_killed_diagnosis(simulated, tmp_path, after):
    out = tmp_path / "d"
    run = subprocess.Popen([sys.executable, "-m", "hdjoint.app.cli", "diagnose", str(simulated), "--out", str(out)],
                           stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, cwd=tmp_path)
    seen: set[int] = set()
    try:
        deadline = time.monotonic() + 60
        while not children(run.pid) and time.monotonic() < deadline and run.poll() is None:
            time.sleep(0.02)
        assert children(run.pid), "the diagnosis forked no helper"
        until = time.monotonic() + after
        while time.monotonic() < until:
            seen.update(descendants(run.pid))
            time.sleep(0.02)
        seen.update(descendants(run.pid))
    finally:
        run.kill()
        run.wait()
    deadline = time.monotonic() + 5
    while any(alive(p) for p in seen) and time.monotonic() < deadline:
        time.sleep(0.05)
    survivors = [p for p in seen if alive(p)]
    for p in survivors:  # do not leave them to the next test
        os.kill(p, signal.SIGKILL)
    assert not survivors, f"orphans of the killed run: {survivors}"
    OutputLock(out).acquire().release()  # the next run is not refused


# ---------------------------------------------------------------- memory

RAISE_AFTER_UNPACKING = """
import sys
from hdjoint.estimation import engines
run = engines.FmuEngine.run
def failing(self, *args):
    run(self, *args)  # the FMU is unpacked by now
    raise MemoryError
engines.FmuEngine.run = failing
from hdjoint.app.cli import main
sys.exit(main(sys.argv[1:]))
"""


def test_out_of_memory_is_one_line_and_leaves_nothing(simulated, tmp_path):
    temp = tmp_path / "tmpdir"
    temp.mkdir()
    out = tmp_path / "est.csv"
    done = subprocess.run([sys.executable, "-c", RAISE_AFTER_UNPACKING, "estimate", str(simulated), "-o", str(out)],
                          capture_output=True, text=True, cwd=tmp_path, timeout=120,
                          env={**os.environ, "TMPDIR": str(temp)})
    assert done.returncode == 1, done.stderr
    assert done.stderr.count("\n") == 1 and "out of memory" in done.stderr, done.stderr
    assert os.listdir(temp) == []  # the unpacked FMU is gone
    assert sorted(os.listdir(tmp_path)) == ["tmpdir"]
