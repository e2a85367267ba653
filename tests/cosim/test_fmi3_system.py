"""The joint-torque-feedback system with the FMI 3.0 twins: the shipped
JointTorqueFeedback.ssp with each FMU replaced by its NAME_fmi3.fmu (same
file name inside the archive, same connections) runs in ecos and in INTO-CPS
Maestro, which import FMI 3.0 Co-Simulation, and gives the FMI 2.0 system's
signals bit for bit. (fmpy's SSP runner loads every FMU as FMI 2.0 and
libcosim imports FMI 1.0 and 2.0 only: both refuse these FMUs;
docs/cosimulation.md.)"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

import numpy as np
import pytest

from hdjoint.fmu import cosim
from hdjoint.fmu.shipped import fmu_path

# The jar scripts/install_cosim.sh fetches into the checkout (as in test_cosim_masters.py).
_JAR = Path(__file__).resolve().parents[2] / "build" / "cosim-tools" / "maestro-3.1.1-jar-with-dependencies.jar"
if _JAR.is_file():
    os.environ.setdefault("HDJOINT_MAESTRO_JAR", str(_JAR))

pytestmark = pytest.mark.slow  # two runs of each master in child processes

STEP = 1e-3
# Maestro's outputs.csv misses its last step on shorter runs (either FMI version).
STOP = {"ecos": 1.0, "maestro": 3.0}


def fmi3_system(ssp: Path, out: Path) -> Path:
    with zipfile.ZipFile(ssp) as src, zipfile.ZipFile(out, "w") as dst:
        replaced = 0
        for item in src.infolist():
            data = src.read(item)
            if item.filename.startswith("resources/") and item.filename.endswith(".fmu"):
                data = fmu_path(Path(item.filename).stem, 3).read_bytes()
                replaced += 1
            dst.writestr(item, data)
    assert replaced == 3
    return out


def run_master(master: str, ssp: Path, out: Path) -> dict[str, np.ndarray]:
    call = {"ecos": f"cosim.run_ecos(sys.argv[1], {STOP['ecos']}, {STEP})",
            "maestro": f"cosim.run_maestro(sys.argv[1], {STOP['maestro']}, {STEP}, cosim.maestro_jar())"}[master]
    code = f"import sys; from hdjoint.fmu import cosim; {call}.save(sys.argv[2])"
    proc = subprocess.run([sys.executable, "-c", code, str(ssp), str(out)], capture_output=True, text=True,
                          timeout=900)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return dict(cosim.Trajectories.load(out).values)


def unavailable(master: str) -> str | None:
    if master == "ecos":
        try:
            import ecospy  # noqa: F401
        except Exception as e:
            return f"ecospy does not import (libtbb12 missing?): {e}"
    if master == "maestro":
        if shutil.which("java") is None or cosim.maestro_jar() is None:
            return "java or the Maestro jar is missing: run scripts/install_cosim.sh"
    return None


@pytest.mark.parametrize("master", ["ecos", "maestro"])
def test_master_runs_the_system_of_fmi3_twins_like_the_fmi2_system(tmp_path, master):
    reason = unavailable(master)
    if reason:
        pytest.skip(reason)
    shipped = cosim.ssp_path("JointTorqueFeedback")
    fmi2 = run_master(master, shipped, tmp_path / "fmi2.npz")
    fmi3 = run_master(master, fmi3_system(shipped, tmp_path / "fmi3.ssp"), tmp_path / "fmi3.npz")
    assert set(fmi2) == set(fmi3) and "joint.tau_joint" in fmi3
    for name, values in fmi2.items():
        assert np.array_equal(values, fmi3[name]), name
    assert np.ptp(fmi3["joint.tau_joint"]) > 0.1
