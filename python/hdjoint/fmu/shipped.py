"""The FMUs this package ships (built by CMake into the wheel)."""
from __future__ import annotations

import shutil
from pathlib import Path

FMU_NAMES = ("JointTorqueEstimator", "HarmonicDriveJoint", "JointController")
_FMU_DIR = Path(__file__).parents[1] / "fmus"  # installed at the package's top by CMake


def shipped_file(folder: Path, name: str, known, suffix: str, what: str) -> Path:
    """Path of a file the package ships (`what`: "FMU", "system"), by name; a clear error for an unknown
    name or a package installed without it."""
    if name not in known:
        raise ValueError(f"unknown {what} '{name}'; known: {', '.join(known)}")
    path = folder / f"{name}{suffix}"
    if not path.is_file():
        raise FileNotFoundError(f"{path} is missing: the package was installed without its {what}s (pip install .)")
    return path


def fmu_path(name: str) -> Path:
    """Path of a shipped FMU, by model identifier."""
    return shipped_file(_FMU_DIR, name, FMU_NAMES, ".fmu", "FMU")


def export_fmus(out_dir: str | Path) -> list[Path]:
    """Copy every FMU into out_dir; returns the written paths."""
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    written = []
    for name in FMU_NAMES:
        target = out / f"{name}.fmu"
        shutil.copyfile(fmu_path(name), target)
        written.append(target)
    return written
