"""Runs the ASan/UBSan-built FMUs of BUILD_DIR (cmake -DHDJOINT_SANITIZE=ON)
through fmpy: each FMU alone on its own defaults, the estimator on a
recording, and the JointTorqueFeedback system. A sanitizer report aborts
the process, so a clean exit means clean runs. The host must have the ASan
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
        out.write(z.read(f"binaries/linux64/{fmu.stem}.so"))
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
    for name in FMUS:
        fmu = build / "fmus" / f"{name}.fmu"
        if not binary_is_sanitized(fmu):
            print(f"{fmu}: not built with -fsanitize=address,undefined", file=sys.stderr)
            return 1
        start = time.monotonic()
        result = simulate_fmu(str(fmu), stop_time=1.0, output_interval=1e-3)
        assert all(np.isfinite(result[n]).all() for n in result.dtype.names), name
        print(f"{name}: 1 s alone, clean ({time.monotonic() - start:.1f} s)")

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
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1] if len(sys.argv) > 1 else "build/sanitize"))
