"""Runs the ASan/UBSan-built FMUs of BUILD_DIR (cmake -DHDJOINT_SANITIZE=ON)
through fmpy: each FMU alone on its own defaults, as FMI 2.0 and FMI 3.0
(NAME_fmi3.fmu), the joint also as Model Exchange with CVode, the estimator
on a recording, the JointTorqueFeedback system, and a short call-sequence
fuzz run (tests/fuzz) over every FMU and interface. A sanitizer report
aborts the process (in a fuzz child: a crash finding), so a clean exit
means clean runs. The host must have the ASan
runtime preloaded (scripts/test.sh does it):

    LD_PRELOAD=$(g++ -print-file-name=libasan.so) ASAN_OPTIONS=detect_leaks=0 \\
        python3 scripts/run_sanitized_fmus.py build/sanitize
"""
from __future__ import annotations

import os
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import numpy as np

FMUS = ("JointTorqueEstimator", "HarmonicDriveJoint", "JointController")


def binary_is_sanitized(fmu: Path) -> bool:
    """The FMU's binary needs libasan and libubsan (a plain build would pass vacuously)."""
    with zipfile.ZipFile(fmu) as z, open(fmu.with_suffix(".so.check"), "wb") as out:
        binary = next(n for n in z.namelist() if n.startswith("binaries/") and n.endswith(".so"))
        out.write(z.read(binary))
    try:
        needed = subprocess.run(["readelf", "-d", str(fmu.with_suffix(".so.check"))], capture_output=True,
                                text=True, check=True).stdout
    finally:
        fmu.with_suffix(".so.check").unlink()
    return "libasan" in needed and "libubsan" in needed


def main(build_dir: str) -> int:
    if "libasan" not in os.environ.get("LD_PRELOAD", ""):
        print("run_sanitized_fmus.py: preload the ASan runtime (LD_PRELOAD=$(g++ -print-file-name=libasan.so))",
              file=sys.stderr)
        return 2
    from fmpy import simulate_fmu
    from hdjoint.fmu import experiments
    from hdjoint.io import parameters
    from hdjoint.fmu.cosim import run_fmpy
    from hdjoint.fmu.runner import run_estimator_fmu

    build = Path(build_dir)
    fmus = [build / "fmus" / f"{name}{suffix}.fmu" for suffix in ("", "_fmi3") for name in FMUS]
    for fmu in fmus:
        if not binary_is_sanitized(fmu):
            print(f"{fmu}: not built with -fsanitize=address,undefined", file=sys.stderr)
            return 1
        runs = [("Co-Simulation", {})]
        if fmu.stem.startswith("HarmonicDriveJoint"):
            runs.append(("Model Exchange", {"fmi_type": "ModelExchange", "relative_tolerance": 1e-8,
                                            "start_values": {"backlash": 2e-4, "hys_H": 0.3},
                                            "input": joint_input()}))
        for interface, options in runs:
            start = time.monotonic()
            result = simulate_fmu(str(fmu), stop_time=1.0, output_interval=1e-3, **options)
            assert all(np.isfinite(result[n]).all() for n in result.dtype.names), fmu.stem
            print(f"{fmu.stem} ({interface}): 1 s alone, clean ({time.monotonic() - start:.1f} s)")

    rec = experiments.run("paper", duration=1.0)
    start = time.monotonic()
    est = run_estimator_fmu(rec.time, rec.i_m, rec.theta_m, rec.theta_l,
                            parameters.for_estimator(parameters.defaults()),
                            fmu=build / "fmus" / "JointTorqueEstimator.fmu")
    assert np.isfinite(est["tau_ukf"]).all()
    print(f"JointTorqueEstimator: 1 s of the paper experiment, clean ({time.monotonic() - start:.1f} s)")

    start = time.monotonic()
    traj = run_fmpy(build / "systems" / "JointTorqueFeedback.ssp", 1.0, 1e-3)
    assert np.isfinite(traj["joint.tau_joint"]).all()
    print(f"JointTorqueFeedback.ssp: 1 s in fmpy, clean ({time.monotonic() - start:.1f} s)")

    return fuzz(fmus, build)


def joint_input():
    """A current that makes the joint move, for the Model Exchange run."""
    t = np.linspace(0.0, 1.0, 101)
    signal = np.zeros(len(t), dtype=[("time", float), ("i_m", float), ("tau_ext", float)])
    signal["time"], signal["i_m"] = t, 0.5 * np.sin(2 * np.pi * 2 * t)
    return signal


def fuzz(fmus, build: Path, sequences: int = 25) -> int:
    """A few call sequences per FMU and interface: a sanitizer abort in a child is a crash finding."""
    import tempfile
    sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "fuzz"))
    from fmi_fuzzer import Campaign, summarise
    targets = list(fmus) + [(f, True) for f in fmus if f.stem.startswith("HarmonicDriveJoint")]
    with tempfile.TemporaryDirectory() as work:
        campaign = Campaign.load(targets, work)
        for name in campaign.fmus:
            start = time.monotonic()
            summary = summarise(campaign.run(name, range(sequences), timeout=10.0))
            found = {c: n for c, n in summary["findings"].items() if n}
            print(f"fuzz {name}: {summary['sequences']} sequences, {summary['calls']} calls, "
                  f"findings {found or 'none'} ({time.monotonic() - start:.1f} s)")
            if found:
                return 1
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/sanitize"))
