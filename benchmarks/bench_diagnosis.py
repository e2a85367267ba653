"""Diagnosis speed: `hdjoint diagnose` end to end (reading the CSV, the
diagnosis, the report) on the paper experiment's 58 s recording, on a 30 s
multisine recording without its torque sensor, and on an hour-long
recording of the same joint, and the in-process diagnosis alone.

The recordings are simulated once (the hour takes several minutes through
the plant FMU; the hour is the paper's 58 s run repeated) and kept in build/bench/. Timings are wall-clock on this
machine; the goals are <= 12 s for 58 s, <= 30 s for the sensorless 30 s
and <= 5 min per hour.
The in-process diagnosis is timed with its hypotheses fitted one after the
other (workers=1) and side by side (one process per core), wall-clock and
CPU (this process and its children). Writes docs/results/diagnosis_speed.md.
Run: python benchmarks/bench_diagnosis.py [--hours 1] [--no-hour]
"""
from __future__ import annotations

import argparse
import os
import pathlib
import subprocess
import sys
import tempfile
import time

from results import ResultsPage

from hdjoint.fmu import experiments
from hdjoint.io import parameters, recording
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.diagnosis.forked import available_cores

CACHE = pathlib.Path(__file__).resolve().parent.parent / "build" / "bench"


def simulated(experiment: str, seconds: float, sensor: bool = True) -> pathlib.Path:
    """An experiment on the realistic joint, `seconds` long, cached (without
    `sensor`: the encoder and current columns only)."""
    path = CACHE / f"{experiment}_{seconds:.0f}s{'' if sensor else '_sensorless'}.csv"
    if not path.exists():
        CACHE.mkdir(parents=True, exist_ok=True)
        print(f"simulating {seconds:.0f} s of the {experiment} experiment (once; cached in {path}) ...", flush=True)
        rec = experiments.run(experiment, joint=experiments.true_joint_parameters(), nominal=parameters.defaults(),
                              duration=seconds)
        if not sensor:
            rec = recording.Recording(time=rec.time, i_m=rec.i_m, theta_m=rec.theta_m, theta_l=rec.theta_l,
                                      tau_sensor=None, extra={}, path=None)
        recording.write_recording(path, rec)
    return path


def time_cli(path: pathlib.Path, params: pathlib.Path) -> float:
    with tempfile.TemporaryDirectory() as out:
        start = time.perf_counter()
        subprocess.run([sys.executable, "-m", "hdjoint.app.cli", "diagnose", str(path), "--params", str(params),
                        "--out", out], check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        return time.perf_counter() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--hours", type=float, default=1.0, help="length of the long recording, hours")
    ap.add_argument("--no-hour", action="store_true", help="skip the long recording")
    args = ap.parse_args()
    params = CACHE / "nominal_params.json"
    CACHE.mkdir(parents=True, exist_ok=True)
    parameters.save(params, parameters.defaults())

    page = ResultsPage("diagnosis_speed", "Diagnosis speed", "python benchmarks/bench_diagnosis.py")
    page.say("| what | wall-clock | CPU (with children) |")
    page.say("|---|---|---|")
    short = simulated("paper", 58.0)
    rec = recording.read_recording(short)
    for workers, label in ((1, "one after the other"), (None, f"side by side ({available_cores()} processes)")):
        cpu, start = _cpu(), time.perf_counter()
        _, doc = diagnose(rec, parameters.defaults(), workers=workers)
        page.say(f"| 58 s recording, in-process, hypotheses {label} | {time.perf_counter() - start:.1f} s | "
                 f"{_cpu() - cpu:.1f} s |")
    page.say(f"| 58 s recording, `hdjoint diagnose` end to end | {time_cli(short, params):.1f} s | |")
    sensorless = simulated("multisine", 30.0, sensor=False)
    page.say(f"| 30 s multisine recording without its torque sensor, `hdjoint diagnose` end to end | "
             f"{time_cli(sensorless, params):.1f} s | |")

    if not args.no_hour:
        long = simulated("paper_repeated", 3600.0 * args.hours)
        seconds = time_cli(long, params)
        page.say(f"| {args.hours:g} h recording, `hdjoint diagnose` end to end | {seconds:.1f} s "
                 f"({seconds / args.hours / 60:.2f} min per hour) | |")
    page.say(f"Verdict on the 58 s recording: {doc['verdict']} "
             f"({', '.join(f['effect'] for f in doc['findings']) or 'no findings'}).")
    page.write()


def _cpu() -> float:
    t = os.times()
    return t.user + t.system + t.children_user + t.children_system


if __name__ == "__main__":
    main()
