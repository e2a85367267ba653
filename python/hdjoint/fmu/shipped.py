"""The FMUs this package ships (built by CMake into the wheel): each model as
FMI 2.0 (`<name>.fmu`) and as FMI 3.0 (`<name>_fmi3.fmu`), from the same C++."""
from __future__ import annotations

import shutil
from pathlib import Path

FMU_NAMES = ("JointTorqueEstimator", "HarmonicDriveJoint", "JointController")
FMI_VERSIONS = (2, 3)
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


def fmu_file_name(name: str, fmi: int = 2) -> str:
    """The file name of a model's FMU for FMI version 2 or 3."""
    if fmi not in FMI_VERSIONS:
        raise ValueError(f"unknown FMI version {fmi!r}; known: 2, 3")
    return f"{name}.fmu" if fmi == 2 else f"{name}_fmi3.fmu"


def fmu_path(name: str, fmi: int = 2) -> Path:
    """Path of a shipped FMU, by model identifier and FMI version (2 or 3)."""
    fmu_file_name(name, fmi)  # the version checked first
    return shipped_file(_FMU_DIR, name, FMU_NAMES, ".fmu" if fmi == 2 else "_fmi3.fmu", "FMU")


def export_fmus(out_dir: str | Path, fmi: tuple[int, ...] = FMI_VERSIONS) -> list[Path]:
    """Copy every FMU of the FMI versions `fmi` into out_dir (each through a
    temporary file, never over a device node, a FIFO or a read-only file);
    returns the written paths."""
    from hdjoint.io.outputs import check_replaceable, open_temp, replace_into, write_error
    out = Path(out_dir)
    pairs = [(name, version, out / fmu_file_name(name, version)) for version in fmi for name in FMU_NAMES]
    for _, _, target in pairs:
        check_replaceable(target)  # before anything is written
    out.mkdir(parents=True, exist_ok=True)
    for name, version, target in pairs:
        try:
            f, tmp = open_temp(target, binary=True)
        except OSError as e:
            raise write_error(target, e) from None
        try:
            with f, open(fmu_path(name, version), "rb") as src:
                shutil.copyfileobj(src, f)
            replace_into(tmp, target)
        except OSError as e:  # a full disk: named with the FMU it was writing
            raise write_error(target, e) from None
        finally:
            Path(tmp).unlink(missing_ok=True)
    return [target for _, _, target in pairs]
