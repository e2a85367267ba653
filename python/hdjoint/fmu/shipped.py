"""The FMUs this package ships (built by CMake into the wheel)."""
from __future__ import annotations

import shutil
from pathlib import Path

FMU_NAMES = ("JointTorqueEstimator", "HarmonicDriveJoint", "JointController")
_FMU_DIR = Path(__file__).parents[1] / "fmus"  # installed at the package's top by CMake


def fmu_path(name: str) -> Path:
    """Path of a shipped FMU, by model identifier."""
    if name not in FMU_NAMES:
        raise ValueError(f"unknown FMU '{name}'; known: {', '.join(FMU_NAMES)}")
    path = _FMU_DIR / f"{name}.fmu"
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing: the package was installed without its FMUs (pip install .)")
    return path


def export_fmus(out_dir: str | Path) -> list[Path]:
    """Copy every FMU into out_dir (each through a temporary file, never over
    a device node, a FIFO or a read-only file); returns the written paths."""
    from hdjoint.io.outputs import check_replaceable, replace_into, temp_path
    out = Path(out_dir)
    targets = [out / f"{name}.fmu" for name in FMU_NAMES]
    for target in targets:
        check_replaceable(target)  # before anything is written
    out.mkdir(parents=True, exist_ok=True)
    for name, target in zip(FMU_NAMES, targets):
        tmp = temp_path(target)
        try:
            shutil.copyfile(fmu_path(name), tmp)
            replace_into(tmp, target)
        finally:
            Path(tmp).unlink(missing_ok=True)
    return targets
