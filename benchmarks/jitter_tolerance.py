"""What timing jitter costs `hdjoint estimate --allow-jitter`, to justify the
threshold above which the command refuses a step as jitter (timebase.JITTER_RTOL).

The paper experiment is simulated on a fine grid (20 µs); a recording at a
nominal 1 ms is taken from it at jittered times t_k = k*1ms + u_k, u_k uniform
in +-JITTER*1ms/2, so consecutive steps are off by up to JITTER of the step
(what the time-base check measures). Each is estimated (FMU engine, Ts 1 ms,
the inputs held between rows) and its torque errors against the sensor are
compared with those of the unjittered recording. Writes
docs/results/jitter_tolerance.md (benchmarks/results.py).

Run: python benchmarks/jitter_tolerance.py [--duration 10] [--seeds 3]
"""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from results import ResultsPage
FINE_STEP = 2e-5
STEP = 1e-3
JITTERS = (0.0, 0.1, 0.2, 0.3, 0.5, 0.8)
ESTIMATES = ("tau_compliance", "tau_ukf", "tau_hat")


def jittered(fine, jitter: float, rng):
    """Rows of FINE nearest to k*STEP + u_k (u_k uniform in +-jitter*STEP/2), strictly increasing."""
    from hdjoint.io.recording import Recording
    n = int((fine.time[-1] - STEP) / STEP)
    wanted = np.arange(1, n) * STEP + rng.uniform(-0.5, 0.5, n - 1) * jitter * STEP
    index = np.unique(np.clip(np.rint(wanted / FINE_STEP).astype(int), 0, len(fine) - 1))
    return Recording(time=fine.time[index] - fine.time[index[0]], i_m=fine.i_m[index], theta_m=fine.theta_m[index],
                     theta_l=fine.theta_l[index], tau_sensor=fine.tau_sensor[index])


def main(argv=None) -> int:
    from hdjoint.fmu import experiments
    from hdjoint.jobs.estimate import Options, estimate_to_file
    from hdjoint.io.recording import write_recording
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=10.0)
    ap.add_argument("--seeds", type=int, default=3)
    args = ap.parse_args(argv)
    fine = experiments.run("paper", sample_time=FINE_STEP, duration=args.duration)
    rms = {j: {name: [] for name in ESTIMATES} for j in JITTERS}
    with tempfile.TemporaryDirectory() as tmp:
        params = Path(tmp) / "params.json"
        params.write_text('{"Ts": 0.001}')
        for jitter in JITTERS:
            for seed in range(args.seeds if jitter else 1):
                rec = jittered(fine, jitter, np.random.default_rng(seed))
                path, out = Path(tmp) / "rec.csv", Path(tmp) / "est.csv"
                write_recording(path, rec)
                figures = estimate_to_file(Options(str(path), str(out), params=str(params), allow_jitter=True)).figures
                for name in ESTIMATES:
                    rms[jitter][name].append(figures[name].rms)
                worst = float(np.max(np.abs(np.diff(rec.time) - STEP))) / STEP
                print(f"jitter {jitter}: steps up to {worst:.0%} off; "
                      + ", ".join(f"{n} {rms[jitter][n][-1]:.4f}" for n in ESTIMATES), file=sys.stderr, flush=True)
    base = {name: rms[0.0][name][0] for name in ESTIMATES}
    page = ResultsPage("jitter_tolerance", "What timing jitter costs `hdjoint estimate --allow-jitter`",
                       "python benchmarks/jitter_tolerance.py")
    page.say(f"The paper experiment, {args.duration:g} s simulated on a {FINE_STEP * 1e6:g} µs grid; rows taken "
             f"at k·1 ms + u_k, steps up to the given fraction of 1 ms off; mean of {args.seeds} seeds; Ts = 1 ms. "
             "RMS error against the sensor, N·m (and relative to the regular recording):")
    page.say("| steps off by up to | " + " | ".join(ESTIMATES) + " |")
    page.say("|---:|" + "---:|" * len(ESTIMATES))
    for jitter in JITTERS:
        cells = []
        for name in ESTIMATES:
            value = float(np.mean(rms[jitter][name]))
            cells.append(f"{value:.4f} ({value / base[name] - 1:+.1%})")
        page.say(f"| {jitter:.0%} | " + " | ".join(cells) + " |")
    page.write()
    return 0


if __name__ == "__main__":
    sys.exit(main())
