"""Independent FMI checkers on all three FMUs: fmpy's validation and
VDMCheck2 (the INTO-CPS VDM-SL model of the FMI 2.0 rules, from Maven
Central; scripts/install_cosim.sh fetches it). Zero findings each; and each
checker does find the problem planted in a broken modelDescription, so a
clean result means something."""
from __future__ import annotations

import shutil
import subprocess
import zipfile
from pathlib import Path

import pytest
from fmpy.validation import validate_fmu

from hdjoint.fmu.shipped import FMU_NAMES, fmu_path

pytestmark = pytest.mark.slow  # VDMCheck2's JVM on each FMU

REPO = Path(__file__).resolve().parents[2]
VDMCHECK = REPO / "build" / "cosim-tools" / "vdmcheck2" / "vdmcheck-1.1.3" / "VDMCheck2.sh"


def test_every_shipped_fmu_is_checked():
    assert set(FMU_NAMES) == {"HarmonicDriveJoint", "JointTorqueEstimator", "JointController"}


@pytest.mark.parametrize("name", FMU_NAMES)
def test_fmpy_validation_finds_nothing(name):
    assert validate_fmu(str(fmu_path(name))) == []


def broken_description(name: str) -> str:
    """The FMU's modelDescription with one rule broken: two variables with
    the same name (the speed gain renamed to the position gain's name)."""
    with zipfile.ZipFile(fmu_path(name)) as z:
        xml = z.read("modelDescription.xml").decode()
    assert xml.count('name="kd"') == 1
    return xml.replace('name="kd"', 'name="kp"')


def test_fmpy_validation_finds_a_planted_error(tmp_path):
    fmu = tmp_path / "broken.fmu"
    with zipfile.ZipFile(fmu_path("JointController")) as src, zipfile.ZipFile(fmu, "w") as dst:
        for item in src.infolist():
            data = src.read(item)
            if item.filename == "modelDescription.xml":
                data = broken_description("JointController").encode()
            dst.writestr(item, data)
    assert validate_fmu(str(fmu)) != []


def vdmcheck(path: Path) -> tuple[int, str]:
    if not VDMCHECK.is_file() or shutil.which("java") is None:
        pytest.skip("VDMCheck2 or java is missing: run scripts/install_cosim.sh")
    proc = subprocess.run([str(VDMCHECK), str(path)], capture_output=True, text=True, timeout=300)
    return proc.returncode, proc.stdout + proc.stderr


@pytest.mark.parametrize("name", FMU_NAMES)
def test_vdmcheck2_finds_nothing(name):
    code, out = vdmcheck(fmu_path(name))
    # The script's exit code is 0 even when java cannot start: read its verdict.
    assert "No errors found." in out and code == 0, out


def test_vdmcheck2_finds_a_planted_error(tmp_path):
    xml = tmp_path / "modelDescription.xml"
    xml.write_text(broken_description("JointController"))
    code, out = vdmcheck(xml)
    assert "Errors found." in out and code != 0, out
