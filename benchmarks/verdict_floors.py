"""False alarms of the verdict's absolute yardstick (diagnosis/verdict/floors.py) and
of the released priors (resize.released) on the independent truth's
controls, with and without a torque sensor: each channel's held-out
residual, its sensors' floor, and the miss beyond the floor as a share of
the torque span, against the default accuracy (rules.ACCURACY_SHARE) and
the hard limit (rules.MAX_MISS_SHARE); and any of mgl, Jl, Kf the released
priors find off.

Both are measured at the calibration stage's set: on a control where
nothing is added or resized, that is the corrected set the verdict reads,
and the calibration costs a fraction of the whole diagnosis. The
whole diagnosis's other reasons for alarming on the same controls are in
diagnosis_independent.md and sensorless_controls.md.

Run: python benchmarks/verdict_floors.py [--seeds 4] [--first-seed 0] [--workers 1] [--sensor yes|no|both] [--table-only]
writes docs/results/verdict_floors.md (and .jsonl, the raw rows; resumable)."""
from __future__ import annotations

import argparse
import time
from dataclasses import replace

from threadpoolctl import threadpool_limits

from hdjoint.diagnosis.fit.nominal_calibration import calibrate, calibration_table
from hdjoint.diagnosis.verdict.floors import accuracy
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint.diagnosis.verdict.resize import released
from hdjoint.diagnosis.search.selection import Selection
from hdjoint.diagnosis.rules import ACCURACY_SHARE, MAX_MISS_SHARE
from hdjoint_truth.cases import CONTROL_CASES, draw, record

import diagnosis_independent as independent
import stamp

RESULTS = independent.ROOT / "docs" / "results" / "verdict_floors.jsonl"
TABLE = RESULTS.with_suffix(".md")
DURATION = 30.0
KEY = ("case", "seed", "run", "sensor")


def run(job: tuple) -> dict:
    name, seed, index, sensor = job
    joint = draw(next(c for c in CONTROL_CASES if c.name == name), seed, DURATION)
    rec = record(joint, index)
    if not sensor:
        rec = replace(rec, tau_sensor=None)
    started = time.perf_counter()
    with threadpool_limits(limits=1, user_api="blas"):
        calibrated = calibrate(prepare(rec, joint.nominal, workers=1))
        size = accuracy(calibrated.objective, calibrated.params, [])
        nothing_added = Selection(calibrated.params, [], calibrated.fit, [], [], [], [], [], [], [])
        gross = released(calibrated.objective, nothing_added,
                         calibration_table(calibrated.objective, calibrated.fit, calibrated.params))
    return {"case": name, "seed": seed, "run": index, "sensor": sensor, "excitation": joint.setups[index].excitation,
            "engine": stamp.engine(), "seconds": round(time.perf_counter() - started, 1), "span": round(size.span, 4),
            "noise": size.noise,
            "released": [c.name for f in gross.findings for c in f.resized] + [u["parameter"] for u in gross.unexplained],
            "channels": {c.channel: {"rms": round(c.rms, 5), "floor": round(c.floor, 5),
                                     "miss_share": round(c.miss / size.span, 5)} for c in size.channels}}


def _worst(row: dict) -> float:
    return max(c["miss_share"] for c in row["channels"].values())


def _alarm(row: dict) -> bool:
    return _worst(row) > ACCURACY_SHARE or bool(row["released"])


def write_table(rows: list[dict]) -> str:
    lines = ["# The verdict's absolute yardstick on controls", "",
             stamp.generated_by("python benchmarks/verdict_floors.py"),
             f"Engine: {', '.join(sorted({r['engine'] for r in rows}))}. The independent truth's controls "
             f"({DURATION:g} s), measured at the calibration stage's set. An alarm: a channel misses more than "
             f"{100 * ACCURACY_SHARE:g} % of the torque span beyond its sensors' floor (the default accuracy); "
             f"the hard limit is {100 * MAX_MISS_SHARE:g} %; or the released priors find mgl, Jl or Kf off.", "",
             "| torque sensor | runs | alarms (either rule) | miss beyond the default accuracy | beyond the hard limit | "
             "released priors find a parameter off | worst miss, share of the span (median / max) |",
             "|---|---|---|---|---|---|---|"]
    for sensor in (True, False):
        group = [r for r in rows if r["sensor"] == sensor]
        if not group:
            continue
        worst = sorted(_worst(r) for r in group)
        lines.append(f"| {'yes' if sensor else 'no'} | {len(group)} | {sum(map(_alarm, group))}/{len(group)} | "
                     f"{sum(w > ACCURACY_SHARE for w in worst)}/{len(group)} | "
                     f"{sum(w > MAX_MISS_SHARE for w in worst)}/{len(group)} | "
                     f"{sum(bool(r['released']) for r in group)}/{len(group)} | "
                     f"{100 * worst[len(worst) // 2]:.1f} % / {100 * worst[-1]:.1f} % |")
    lines += ["", "| case | seed | run | sensor | span (N.m) | per channel: held-out RMS / floor (N.m), miss (% of span) "
              "| current noise (A, source) | released off | s |", "|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        channels = "; ".join(f"{n}: {c['rms']:.3g} / {c['floor']:.2g}, {100 * c['miss_share']:.1f} %"
                             for n, c in r["channels"].items())
        current = r["noise"]["i_m"]
        lines.append(f"| {r['case']} | {r['seed']} | {r['run']} | {'yes' if r['sensor'] else 'no'} | {r['span']:.3g} | "
                     f"{channels} | {current['value']:.2g} ({current['source']}) | {', '.join(r['released']) or '-'} | "
                     f"{r['seconds']} |")
    text = "\n".join(lines) + "\n"
    TABLE.write_text(text)
    return text


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--seeds", type=int, default=4)
    parser.add_argument("--first-seed", type=int, default=0)
    parser.add_argument("--workers", type=int, default=1)
    parser.add_argument("--sensor", choices=("yes", "no", "both"), default="both")
    parser.add_argument("--table-only", action="store_true", help="rebuild the table from the rows written so far")
    args = parser.parse_args()
    if args.table_only:
        rows = independent.load_results(RESULTS, KEY)
        print(write_table(sorted(rows, key=lambda r: (not r["sensor"], r["case"], r["seed"], r["run"]))))
        return
    sensors = {"yes": (True,), "no": (False,), "both": (True, False)}[args.sensor]
    jobs = []
    for seed in range(args.first_seed, args.first_seed + args.seeds):
        for case in CONTROL_CASES:
            # Both recordings of a control, as diagnosis_independent.py diagnoses them.
            jobs += [(case.name, seed, index, sensor) for sensor in sensors for index in (0, 1)]
    rows = independent.run_pending(jobs, run, RESULTS, KEY, args.workers,
                                   lambda r: f"{r['case']} s{r['seed']} run {r['run']} sensor {r['sensor']}: "
                                             f"worst miss {100 * _worst(r):.1f} %, released {r['released']} ({r['seconds']} s)")
    print(write_table(sorted(rows, key=lambda r: (not r["sensor"], r["case"], r["seed"], r["run"]))))


if __name__ == "__main__":
    main()
