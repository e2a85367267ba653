"""How often the calibration's 95 % intervals contain the truth.

On the independent truth (hdjoint_truth: its own friction law and
smoothing, integrator, sensor chain, structural damping, parameters off by
up to 10 %), controls on every excitation kind: calibrate the nominal model
(the diagnosis's first step) and check, for every calibrated parameter
whose true value is defined, whether its interval contains it: the Laplace
one, the cluster-robust (sandwich) one, and the wider of the two (what
`hdjoint diagnose` reports). Parameters without a defined truth are left
out: the encoder offset a0 (placed by the diagnosis), `wg_load` (the truth
loads its wave generator its own way) and `omega_fc` when the truth's
friction is LuGre.

The raw intervals (Laplace, sandwich) are too narrow where the truth's
form differs (bias, not noise): --fit-factors A-B sets each parameter's
model-form factor, the 95th percentile of abs(error) / std over seeds A-B
divided by 1.96 (at least 1), and writes python/hdjoint/diagnosis/fit/model_form_factors.json,
which the diagnosis then multiplies its intervals by; the coverage that
counts is the one on the other seeds.

Run: python benchmarks/interval_coverage.py [--first-seed 0] [--seeds 8] [--duration 30]
       [--fit-factors 0-7] [--table-only]
Results are appended to docs/results/interval_coverage.jsonl (one line per
recording, resumable); docs/results/interval_coverage.md is rebuilt from all lines.
"""
from __future__ import annotations

import argparse
import json
from collections import defaultdict
from pathlib import Path

import numpy as np
from results import RESULTS_DIR, ResultsPage
from threadpoolctl import threadpool_limits

import stamp
from hdjoint.diagnosis.fit.nominal_calibration import calibrate as calibrate_stage
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint_truth.cases import CONTROL_CASES, draw, record

Z95 = 1.959964
UNDEFINED = ("a0", "wg_load")
RAW = RESULTS_DIR / "interval_coverage.jsonl"
# The source tree's copy (the installed package reads the one the wheel carries).
FACTORS = Path(__file__).resolve().parents[1] / "python" / "hdjoint" / "diagnosis" / "fit" / "model_form_factors.json"


def true_value(name: str, joint) -> float | None:
    """The truth's value of a calibrated parameter, as the nominal model means it."""
    if name in UNDEFINED:
        return None
    if name == "omega_fc":
        return joint.form.omega_fc if joint.form.friction == "tanh" else None
    if name == "Kt":  # the current sensor's gain error scales what Kt multiplies
        return joint.truth["Kt"] / (1.0 + joint.setups[0].current_sensor.gain_error)
    return joint.truth.get(name)


def calibrate(case, seed: int, duration: float) -> list[dict]:
    """Each calibrated parameter's error against the truth, in units of its
    raw posterior std (the wider of Laplace and sandwich, before any factor)."""
    joint = draw(case, seed, duration)
    setup = prepare(record(joint, 0), joint.nominal)
    with threadpool_limits(limits=1, user_api="blas"):
        calibrated = calibrate_stage(setup)
        p, fit, diag = calibrated.params, calibrated.fit, calibrated.objective
    rows = []
    for name in diag.calibrated_names:
        truth = true_value(name, joint)
        if truth is None:
            continue
        laplace, robust = fit.std_laplace[name], fit.std_robust[name]
        rows.append({"name": name, "kind": case.excitation, "seed": seed, "error": p[name] - truth,
                     "laplace": laplace, "robust": robust, "raw": max(laplace, robust)})
    return rows


def load(path: Path = RAW) -> list[dict]:
    """Every recording's rows (the first line of each recording, should parts have run twice)."""
    seen, rows = set(), []
    for line in path.read_text().splitlines() if path.exists() else []:
        record_ = json.loads(line)
        key = (record_["kind"], record_["seed"], record_["duration"])
        if key not in seen:
            seen.add(key)
            rows += record_["rows"]
    return rows


def fit_factors(rows: list[dict]) -> dict[str, float]:
    """Per parameter: how much wider than its raw std an interval must be to
    contain the truth in 95 % of `rows` (at least 1)."""
    by_name = defaultdict(list)
    for r in rows:
        if r["raw"] > 0:  # a zero std: the fit sat at a bound of the parameter's range, no posterior to widen
            by_name[r["name"]].append(abs(r["error"]) / r["raw"])
    return {n: round(max(1.0, float(np.quantile(z, 0.95)) / Z95), 3) for n, z in by_name.items()}


def _seeds(text: str) -> range:
    first, _, last = text.partition("-")
    return range(int(first), int(last or first) + 1)


def write_factors(rows: list[dict], seeds: range, duration: float) -> dict:
    train = [r for r in rows if r["seed"] in seeds]
    factors = fit_factors(train)
    FACTORS.write_text(json.dumps({
        "factors": factors,
        "measured": {"by": f"python benchmarks/interval_coverage.py --fit-factors {seeds[0]}-{seeds[-1]}",
                     "seeds": [seeds[0], seeds[-1]], "recordings": len({(r["kind"], r["seed"]) for r in train}),
                     "duration_s": duration, "commit": stamp.commit(),
                     "date": stamp.now()}}, indent=1) + "\n")
    print(f"wrote {FACTORS}")
    return factors


def _pct(flags) -> str:
    flags = list(flags)
    return f"{100 * sum(flags) / len(flags):.0f} %" if flags else "-"


def _covered(r: dict, std: float) -> bool:
    return abs(r["error"]) <= Z95 * std


def write_table(page: ResultsPage, rows: list[dict], factors: dict, trained: list[int] | None) -> None:
    runs = len({(r["kind"], r["seed"]) for r in rows})
    seeds = sorted({r["seed"] for r in rows})
    held = [r for r in rows if trained is None or not trained[0] <= r["seed"] <= trained[1]]
    page.say(f"{runs} control recordings (seeds {seeds[0]}-{seeds[-1]}, every excitation kind), {len(rows)} "
             "calibrated parameters with a defined truth. A 95 % interval should contain the truth 95 % of the time.")
    page.say("Model-form factors: " + (f"fitted on seeds {trained[0]}-{trained[1]}; the columns 'reported' count "
                                       f"only the other seeds ({len(held)} checks)." if trained else
                                       "none (every factor 1)."))
    page.say("| parameter | checks | Laplace | sandwich | wider of the two | factor | reported (wider x factor), "
             "held-out seeds | median abs(error) / raw std |")
    page.say("|---|---|---|---|---|---|---|---|")
    by_name = defaultdict(list)
    for r in rows:
        by_name[r["name"]].append(r)
    for name, group in list(by_name.items()) + [("all", rows)]:
        errors = sorted(abs(r["error"]) / max(r["raw"], 1e-300) for r in group)
        out = [r for r in held if name in ("all", r["name"])]
        page.say(f"| {name} | {len(group)} | {_pct(_covered(r, r['laplace']) for r in group)} | "
                 f"{_pct(_covered(r, r['robust']) for r in group)} | {_pct(_covered(r, r['raw']) for r in group)} | "
                 f"{factors.get(name, 1.0) if name != 'all' else '-'} | "
                 f"{_pct(_covered(r, r['raw'] * factors.get(r['name'], 1.0)) for r in out)} | "
                 f"{errors[len(errors) // 2]:.2f} |")
    page.say("Per excitation (reported intervals, held-out seeds): " + ", ".join(
        f"{kind} {_pct(_covered(r, r['raw'] * factors.get(r['name'], 1.0)) for r in held if r['kind'] == kind)}"
        for kind in dict.fromkeys(r["kind"] for r in rows)) + ".")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first-seed", type=int, default=0)
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--duration", type=float, default=30.0)
    ap.add_argument("--fit-factors", metavar="A-B", help="set the model-form factors from seeds A-B")
    ap.add_argument("--table-only", action="store_true")
    args = ap.parse_args()
    if not args.table_only:
        for seed in range(args.first_seed, args.first_seed + args.seeds):
            for case in CONTROL_CASES:
                done = {(r["kind"], r["seed"]) for r in load()}  # other parts may run beside this one
                if (case.excitation, seed) in done:
                    continue
                rows = calibrate(case, seed, args.duration)
                with RAW.open("a") as f:
                    f.write(json.dumps({"kind": case.excitation, "seed": seed, "duration": args.duration,
                                        "rows": rows}) + "\n")
                print(f"seed {seed} {case.excitation}: {len(rows)} parameter checks", flush=True)
    rows = load()
    if args.fit_factors:
        write_factors(rows, _seeds(args.fit_factors), args.duration)
    stored = json.loads(FACTORS.read_text()) if FACTORS.exists() else None
    page = ResultsPage("interval_coverage", "Calibration intervals: coverage of the truth",
                       "python benchmarks/interval_coverage.py" + (f" --fit-factors {args.fit_factors}"
                                                                  if args.fit_factors else ""))
    write_table(page, rows, stored["factors"] if stored else {}, stored["measured"]["seeds"] if stored else None)
    page.write()


if __name__ == "__main__":
    main()
