"""The README's everyday commands run as written, one after the other, in a
folder holding what they name (a parameter file, recordings of one joint, a
fleet's logs and its parameter map), as a newcomer's own files would be; each
writes what its comment promises."""
import json
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from hdjoint.fleet.generate import generate
from hdjoint.fmu import experiments
from hdjoint.io import parameters
from hdjoint.io.recording import Recording, write_recording

pytestmark = pytest.mark.slow  # diagnoses and a Dask cluster: about two minutes

ROOT = Path(__file__).resolve().parents[2]


def everyday_commands() -> list[str]:
    """The command lines of the README's "Everyday use" block, comments dropped."""
    section = (ROOT / "README.md").read_text().split("## Everyday use", 1)[1]
    block = re.search(r"```sh\n(.*?)```", section, re.S).group(1)
    return [line.split("  #", 1)[0].strip() for line in block.splitlines() if line.strip()]


def _recording(folder: Path, name: str, experiment: str, seconds: float, sensor: bool = True) -> None:
    rec = experiments.run(experiment, duration=seconds)
    if not sensor:
        rec = Recording(time=rec.time, i_m=rec.i_m, theta_m=rec.theta_m, theta_l=rec.theta_l, tau_sensor=None,
                        extra={}, path=None)
    write_recording(str(folder / name), rec)


@pytest.fixture(scope="module")
def workspace(tmp_path_factory) -> Path:
    folder = tmp_path_factory.mktemp("everyday")
    parameters.save(folder / "joint.json", parameters.defaults())
    _recording(folder, "bench.csv", "multisine", 10.0, sensor=False)  # the shop floor's: encoders and current
    for name, experiment in (("a.csv", "paper"), ("b.csv", "sweep"), ("c.csv", "multisine")):
        _recording(folder, name, experiment, 8.0)
    _recording(folder, "run.csv", "paper", 8.0, sensor=False)
    generate(folder, joints=1, days=2, duration=4.0)  # logs/robot1/j1/<date>.csv and params-map.json
    shutil.copy(folder / "params-map.json", folder / "map.json")
    return folder


def test_the_readme_names_the_commands_a_user_runs():
    commands = everyday_commands()
    assert len(commands) >= 8 and all(c.startswith("hdjoint ") for c in commands)
    assert any("--calibrate-from" in c for c in commands)


def test_every_everyday_command_runs_as_written(workspace):
    hdjoint = shutil.which("hdjoint")
    assert hdjoint, "the hdjoint command is not installed"
    for command in everyday_commands():
        run = subprocess.run(["bash", "-euc", command], cwd=workspace, capture_output=True, text=True, timeout=900,
                             env={"PATH": f"{Path(sys.executable).parent}:{Path(hdjoint).parent}:/usr/bin:/bin",
                                  "HOME": str(workspace)})
        assert run.returncode == 0, f"{command}\n{run.stderr[-3000:]}"
        if "--calibrate-from" in command:  # the calibrated set and its intervals beside the estimates
            calibration = json.loads((workspace / "est.calibration.json").read_text())
            assert calibration["calibrated_from"] == ["bench.csv"] and calibration["parameters"]
            assert (workspace / "est.params.json").is_file()
    assert sorted(p.name for p in (workspace / "fmus").iterdir() if p.suffix == ".fmu")
    assert "tau_sensor" in (workspace / "paper.csv").read_text().split("\n", 1)[0]
    estimates = np.genfromtxt(workspace / "est.csv", delimiter=",", names=True)
    assert len(estimates) > 1000 and np.isfinite(estimates["tau_hat"]).all()
    diag = json.loads((workspace / "diag" / "findings.json").read_text())
    assert diag["validation"] and {"verdict", "params"} <= set(diag)
    assert (workspace / "fleet" / "fleet.parquet").is_file() and (workspace / "fleet" / "fleet.html").is_file()
