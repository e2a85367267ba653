"""Fleet speed and proof: recordings per minute on a LocalCluster with 1 and
2 worker processes, Dask's per-task overhead, the fleet machinery's own
cost per recording, and the drift ranking of the generated fleet (4 joints
x 6 days of 20 s recordings; one joint's Coulomb friction and another's
kinematic error grow over the days). Writes docs/results/fleet.md.

The fleet is generated once into build/bench/fleet/ and its diagnosis kept
in build/bench/fleet-out/ (a rerun resumes it). The machine is shared: the
load average is printed with the figures.
Run: python benchmarks/bench_fleet.py [--speedup 8] [--command diagnose] [--no-proof]
"""
from __future__ import annotations

import argparse
import json
import os
import pathlib
import tempfile
import time

import numpy as np

import stamp
from hdjoint.fleet import trend
from hdjoint.fleet.generate import JOINT_PATTERN, generate
from hdjoint.fleet.run import connect, run_fleet

ROOT = pathlib.Path(__file__).resolve().parent.parent
CACHE = ROOT / "build" / "bench"
RESULTS = ROOT / "docs" / "results" / "fleet.md"
QUANTITIES_PER_JOINT = 7  # what a diagnosis of the paper experiment moves: Fc, kinematic amplitude, Kt, Jm, Bm, Cf, Kw


def _noop(x):
    return x


def load() -> str:
    return "load average " + ", ".join(f"{x:.1f}" for x in os.getloadavg())


def fleet(days: int, joints: int) -> tuple[pathlib.Path, pathlib.Path]:
    root = CACHE / "fleet"
    pmap = root / "params-map.json"
    if not pmap.exists():
        print(f"generating {joints} joints x {days} days into {root} (once) ...", flush=True)
        generate(root, joints=joints, days=days)
    return root, pmap


def spread(paths: list[str], n: int) -> list[str]:
    """n recordings taken across all joints (every k-th of the sorted list)."""
    step = max(1, len(paths) // n)
    return paths[::step][:n]


def throughput(command: str, recordings: list[str], pmap: pathlib.Path, workers: int) -> dict:
    client = connect(None, workers, 2)
    try:
        client.map(_noop, range(workers * 4)).__len__()  # nothing warm yet: imports happen in the tasks
        with tempfile.TemporaryDirectory() as out:
            start = time.perf_counter()
            summary = run_fleet(command, recordings, out, params_map=str(pmap), joint_pattern=JOINT_PATTERN,
                                client=client, show_progress=False, write_report=False,
                                options={"engine": "fmu"} if command == "estimate" else {})
            wall = time.perf_counter() - start
            start = time.perf_counter()
            run_fleet(command, recordings, out, params_map=str(pmap), joint_pattern=JOINT_PATTERN, client=client,
                      show_progress=False, write_report=False,
                      options={"engine": "fmu"} if command == "estimate" else {})
            cached = time.perf_counter() - start
        task = float(np.mean([r["seconds"] for r in summary.rows]))
        assert summary.failed == 0, [r["error"] for r in summary.rows if r["error"]]
        # Dask's own cost per task: a round trip of tasks that do nothing.
        n = 400
        start = time.perf_counter()
        client.gather(client.map(_noop, range(n), pure=False))
        dask_overhead = (time.perf_counter() - start) / n
    finally:
        cluster = client.cluster
        client.close()
        cluster.close()
    return {"workers": workers, "recordings": len(recordings), "wall": wall,
            "per_minute": 60 * len(recordings) / wall, "task": task, "cached_per_recording": cached / len(recordings),
            "dask_per_task": dask_overhead, "load": load()}


def proof(root: pathlib.Path, pmap: pathlib.Path) -> tuple[list, dict, float]:
    out = CACHE / "fleet-out"
    start = time.perf_counter()
    summary = run_fleet("diagnose", [str(root / "logs/**/*.csv")], out, params_map=str(pmap),
                        joint_pattern=JOINT_PATTERN, workers=2)
    truth = json.loads((root / "truth.json").read_text())["drifts"]
    return trend.rank_joints(summary.rows), truth, time.perf_counter() - start


def null_false_alarm_rate(days: int, quantities: int, trials: int = 20000, seed: int = 11) -> tuple[float, float]:
    """Per-quantity and per-joint (Bonferroni over `quantities`) false-alarm
    rates of the trend test on series without drift: scatter of unequal
    size and intervals off by a common factor of 0.3-3."""
    rng = np.random.default_rng(seed)
    x = np.arange(days, dtype=float)
    flagged_q, flagged_j = 0, 0
    for _ in range(trials // quantities):
        ps = []
        for _ in range(quantities):
            se = rng.uniform(0.5, 2.0, days)
            y = rng.normal(0.0, se)
            half = trend.Z95 * se * rng.uniform(0.3, 3.0)
            ps.append(trend.slope_test(x, y, y - half, y + half)[2])
        flagged_q += sum(p < trend.ALPHA for p in ps)
        flagged_j += min(ps) * quantities < trend.ALPHA
    return flagged_q / (trials // quantities * quantities), flagged_j / (trials // quantities)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--command", choices=("diagnose", "estimate"), default="diagnose")
    ap.add_argument("--speedup", type=int, default=8, help="recordings for the 1 vs 2 worker comparison")
    ap.add_argument("--days", type=int, default=6)
    ap.add_argument("--joints", type=int, default=4)
    ap.add_argument("--no-proof", action="store_true", help="skip diagnosing the whole fleet")
    args = ap.parse_args()
    root, pmap = fleet(args.days, args.joints)
    recordings = spread(sorted(str(p) for p in (root / "logs").rglob("*.csv")), args.speedup)
    lines = ["# Fleet benchmark", "",
             stamp.generated_by(f"python benchmarks/bench_fleet.py --command {args.command}"), "",
             f"## Throughput: `fleet {args.command}`, {len(recordings)} recordings of 20 s", "",
             "| workers | recordings/min | wall (s) | mean task (s) | fleet bookkeeping per reused recording (s) "
             "| Dask per no-op task (ms) | load during |", "|---|---|---|---|---|---|---|"]
    runs = []
    for workers in (1, 2):
        r = throughput(args.command, recordings, pmap, workers)
        runs.append(r)
        print(f"{workers} worker(s): {r['per_minute']:.2f} recordings/min ({r['wall']:.1f} s for {r['recordings']}; "
              f"task {r['task']:.1f} s; cached rerun {r['cached_per_recording'] * 1e3:.0f} ms/recording; "
              f"Dask {r['dask_per_task'] * 1e3:.1f} ms/task; {r['load']})", flush=True)
        lines.append(f"| {workers} | {r['per_minute']:.2f} | {r['wall']:.1f} | {r['task']:.2f} | "
                     f"{r['cached_per_recording']:.3f} | {r['dask_per_task'] * 1e3:.2f} | {r['load']} |")
    speedup = runs[1]["per_minute"] / runs[0]["per_minute"]
    print(f"speed-up with 2 workers: {speedup:.2f}x (goal >= 1.8x)")
    lines += ["", f"Speed-up with 2 workers: **{speedup:.2f}x** (goal >= 1.8x).", ""]
    q_rate, j_rate = null_false_alarm_rate(args.days, QUANTITIES_PER_JOINT)
    lines += ["## Trend test false-alarm rate (joints without drift, simulated)", "",
              f"{args.days} points, unequal scatter, intervals off by a factor 0.3-3: "
              f"per quantity {q_rate:.3f}, per joint (Bonferroni over {QUANTITIES_PER_JOINT} quantities) "
              f"{j_rate:.3f} at alpha = {trend.ALPHA}.", ""]
    print(f"false alarms without drift: per quantity {q_rate:.3f}, per joint {j_rate:.3f}")
    if not args.no_proof:
        ranked, truth, seconds = proof(root, pmap)
        lines += [f"## Proof: the generated fleet ({args.joints} joints x {args.days} days), `fleet diagnose` "
                  f"on 2 workers ({seconds:.0f} s including reused results)", "",
                  "| rank | joint | drift p (Bonferroni) | drifting | effect | quantity | direction | change | truth |",
                  "|---|---|---|---|---|---|---|---|---|"]
        for i, d in enumerate(ranked):
            s = d.strongest
            t = truth.get(d.joint)
            lines.append(f"| {i + 1} | {d.joint} | {d.p_value:.2g} | {'yes' if d.drifting else 'no'} | {d.effect} | "
                         f"{s.quantity if s else ''} | {d.direction} | {100 * s.change:+.0f} % | "
                         f"{(t['effect'] + ' +' + format(100 * t['per_day'], '.0f') + ' %/day') if t else 'no drift'} |"
                         if s else f"| {i + 1} | {d.joint} | | | | | | | |")
        drifting = {j for j, t in truth.items() if t}
        top = [d.joint for d in ranked[:len(drifting)]]
        named = all(d.effect == truth[d.joint]["effect"] for d in ranked[:len(drifting)] if truth.get(d.joint))
        null_flags = sum(d.drifting for d in ranked if not truth.get(d.joint))
        verdict = (f"The drifting joints rank first: {'yes' if set(top) == drifting else 'NO'}; their growing effect "
                   f"named: {'yes' if named else 'NO'}; joints without drift flagged: {null_flags} of "
                   f"{len(ranked) - len(drifting)}.")
        print(verdict)
        lines += ["", verdict, ""]
    lines += [f"Load at the end: {load()}.", ""]
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text("\n".join(lines))
    print(f"wrote {RESULTS}")


if __name__ == "__main__":
    main()
