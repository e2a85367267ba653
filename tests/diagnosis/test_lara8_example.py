"""examples/lara8 as a newcomer uses it: its commands run as written on the
real recordings, with the parameter files it ships, and give the README's
LARA8 table, which is the one benchmarks/lara8_table.py generated
(docs/results/lara8.json)."""
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "benchmarks"))
import lara8_table

EXAMPLE = ROOT / "examples" / "lara8"
DATA = ROOT / "tests" / "data" / "lara8"
ROWS = {r["recording"]: r for r in json.loads((ROOT / "docs/results/lara8.json").read_text())}


def _commands() -> str:
    """The example's shell block, with D the copy of the recordings the tests carry (its comment's alternative)."""
    block = re.search(r"```sh\n(.*?)```", (EXAMPLE / "README.md").read_text(), re.DOTALL).group(1)
    assert block.startswith("D=")
    return f"D={DATA}\n" + block.split("\n", 1)[1]


def _shown(findings: dict) -> dict:
    """A diagnosis as the generated table records it."""
    return {"verdict": findings["verdict"], "findings": [f"{f['effect']} ({f['kind']})" for f in findings["findings"]]}


def test_the_readme_lara8_table_is_the_generated_one():
    """Every figure of the README's LARA8 table comes from docs/results/lara8.json, as the benchmark formats it."""
    generated = lara8_table.readme_table(list(ROWS.values()))
    readme = (ROOT / "README.md").read_text().splitlines()
    start = readme.index(generated[0])
    assert readme[start:start + len(generated)] == generated
    assert "\n".join(generated) in (ROOT / "docs/results/lara8.md").read_text()


@pytest.mark.slow
def test_the_examples_commands_run_as_written_and_give_the_readme_row(tmp_path):
    """Diagnose, estimate with the shipped set (its a0 is the joint's encoder zero: with a0 = 0 the
    torsion was 0.9 rad, and `estimate` refused it as singular), estimate with the corrected set; the
    logger's jitter is taken with --allow-jitter, the current's sign turned with --current-sign -1."""
    work = tmp_path / "lara8"
    shutil.copytree(EXAMPLE, work)
    run = subprocess.run(["bash", "-euc", _commands()], cwd=work, check=False, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    assert "singular" not in run.stderr
    for name in ("est.csv", "corrected.csv"):
        est = np.genfromtxt(work / name, delimiter=",", names=True)
        assert len(est) > 1000 and np.all(np.isfinite(est["tau_hat"])), name
    found = json.loads((work / "out" / "findings.json").read_text())
    shipped = ROWS["joint1_jog.csv"]["yardstick"]["examples/lara8"]
    assert _shown(found) == {k: shipped[k] for k in ("verdict", "findings")}


@pytest.mark.slow
@pytest.mark.parametrize("recording", ["joint1_jog_linear_mass.csv", "joint2_jog_joint_mass.csv",
                                       "joint3_jog_linear_mass.csv"])
def test_the_same_commands_give_the_other_readme_rows(recording, tmp_path):
    joint = recording.split("_")[0]
    sign = ["--current-sign", "-1"] if lara8_table.CURRENT_SIGN[joint] < 0 else []
    run = subprocess.run(["hdjoint", "diagnose", str(DATA / recording), "--params",
                          str(EXAMPLE / f"{joint}_params.json"), *sign, "--out", str(tmp_path / "out")],
                         check=False, capture_output=True, text=True, timeout=600)
    assert run.returncode == 0, run.stderr
    shipped = ROWS[recording]["yardstick"]["examples/lara8"]
    assert _shown(json.loads((tmp_path / "out" / "findings.json").read_text())) == {
        k: shipped[k] for k in ("verdict", "findings")}
