"""The main job on built-in data: build artefacts, simulate the paper's
experiment, estimate torque through the estimator FMU, reproduce the
paper's table, then the mission (demo_story.py): a hidden effect named
without a torque sensor, closed on a second recording, told on one screen
(demo_page.py)."""
from __future__ import annotations

import sys
import time
from pathlib import Path

from hdjoint.app import demo_page, demo_story
from hdjoint.estimation.metrics import error_figures
from hdjoint.estimation.paper_table import reproduce
from hdjoint.fmu import experiments
from hdjoint.fmu.runner import run_estimator_fmu
from hdjoint.fmu.shipped import export_fmus
from hdjoint.io import figures as plots
from hdjoint.io import parameters
from hdjoint.io.recording import write_csv, write_recording
from hdjoint.jobs.paper_joint_calibration import sensorless_set
from hdjoint.io.outputs import printable, write_whole


def _say(message: str) -> None:
    print(message, file=sys.stderr, flush=True)


def run_demo(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    started = time.perf_counter()
    _say(f"[1/5] FMUs -> {printable(out / 'fmus')}")
    export_fmus(out / "fmus")

    _say("[2/5] simulating the paper experiment (HarmonicDriveJoint.fmu under position control, 58 s)")
    rec = experiments.run("paper")
    write_recording(out / "paper_recording.csv", rec)

    _say("[3/5] estimating torque through JointTorqueEstimator.fmu (fmpy)")
    est_params = parameters.for_estimator(parameters.defaults())
    est = run_estimator_fmu(rec.time, rec.i_m, rec.theta_m, rec.theta_l, est_params)
    write_csv(out / "paper_estimates.csv", {"time": rec.time, **est})
    fmu_check = error_figures(est["tau_ukf"], rec.extra["tau_joint"])

    _say("[4/5] the paper's table: compliance model vs UKF (default and fairly tuned), tau_hat, tau_smooth, "
         "and tau_hat after a sensorless calibration on another run")
    table = reproduce(rec, calibrated=sensorless_set(rec, out))  # calibrated on another run, no torque sensor
    write_whole(out / "paper_table.md", table.markdown() + "\n")
    plots.save(plots.torque_comparison(rec.time, table.estimates, "Paper experiment: estimates vs true torque"),
               out / "paper_torque.png")
    print(table.markdown())
    print(f"\nUKF through the FMU: RMS {fmu_check.rms:.3f} N.m (same as the batch path's default row)")
    print(f"tuned UKF settings: {parameters.values_in_text(table.tuned_settings)}")

    _mission(out)
    print(f"outputs in {printable(out)} ({time.perf_counter() - started:.1f} s); open {printable(out / 'index.html')}")


def _mission(out: Path) -> None:
    """Step 5: the hidden effect named and closed, printed and written as the demo's first screen."""
    _say("[5/5] the mission: a hidden effect named without a torque sensor, closed on a second recording")
    story = demo_story.run_story(out, _say)
    demo_page.write_summary(out, story)
    demo_page.write_index(out, story)
    print(f"\n{demo_page.TITLE}")
    for line in demo_page.summary_lines(story):
        print(f"- {line}")
