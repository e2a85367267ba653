"""How often the calibration's 95 % intervals contain the truth.

On the independent truth (hdjoint.truth: its own friction law and
smoothing, integrator, sensor chain, structural damping, parameters off by
up to 10 %), controls on every excitation kind: calibrate the nominal model
(the diagnosis's first step) and check, for every calibrated parameter
whose true value is defined, whether its interval contains it: the Laplace
one, the cluster-robust (sandwich) one, and the wider of the two (what
`hdjoint diagnose` reports). Parameters without a defined truth are left
out: the encoder offset a0 (placed by the diagnosis), `wg_load` (the truth
loads its wave generator its own way) and `omega_fc` when the truth's
friction is LuGre.

Run: python benchmarks/interval_coverage.py [--seeds 8] [--duration 30]
writes docs/results/interval_coverage.md.
"""
from __future__ import annotations

import argparse
from collections import defaultdict

from results import ResultsPage
from threadpoolctl import threadpool_limits

from hdjoint.diagnosis import Diagnosis
from hdjoint.truth.cases import CONTROL_CASES, draw, record

Z95 = 1.959964
UNDEFINED = ("a0", "wg_load")


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
    joint = draw(case, seed, duration)
    diag = Diagnosis(record(joint, 0), joint.nominal)
    with threadpool_limits(limits=1, user_api="blas"):
        p, fit = diag.calibrate()
    rows = []
    for name in diag.calibrated_names:
        truth = true_value(name, joint)
        if truth is None:
            continue
        error = abs(p[name] - truth)
        rows.append({"name": name, "kind": case.excitation, "seed": seed,
                     "laplace": error <= Z95 * fit.std_laplace[name], "robust": error <= Z95 * fit.std_robust[name],
                     "reported": error <= Z95 * fit.std[name], "width_ratio": fit.std_robust[name] /
                     max(fit.std_laplace[name], 1e-300), "z_error": (p[name] - truth) / max(fit.std[name], 1e-300)})
    return rows


def _pct(flags) -> str:
    flags = list(flags)
    return f"{100 * sum(flags) / len(flags):.0f} %" if flags else "-"


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seeds", type=int, default=8)
    ap.add_argument("--duration", type=float, default=30.0)
    args = ap.parse_args()
    page = ResultsPage("interval_coverage", "Calibration intervals: coverage of the truth",
                       f"python benchmarks/interval_coverage.py --seeds {args.seeds} --duration {args.duration:g}")
    rows = []
    for seed in range(args.seeds):
        for case in CONTROL_CASES:
            rows += calibrate(case, seed, args.duration)
            print(f"seed {seed} {case.excitation}: {len(rows)} parameter checks so far", flush=True)
    runs = len({(r["kind"], r["seed"]) for r in rows})
    page.say(f"{runs} control recordings of {args.duration:g} s (seeds 0-{args.seeds - 1}, every excitation kind), "
             f"{len(rows)} calibrated parameters with a defined truth. A 95 % interval should contain the truth "
             "95 % of the time.")
    page.say("| parameter | checks | Laplace | sandwich | reported (wider) | median sandwich / Laplace width "
             "| median abs(error) / reported std |")
    page.say("|---|---|---|---|---|---|---|")
    by_name = defaultdict(list)
    for r in rows:
        by_name[r["name"]].append(r)
    for name, group in list(by_name.items()) + [("all", rows)]:
        ratios = sorted(r["width_ratio"] for r in group)
        errors = sorted(abs(r["z_error"]) for r in group)
        page.say(f"| {name} | {len(group)} | {_pct(r['laplace'] for r in group)} | {_pct(r['robust'] for r in group)} "
                 f"| {_pct(r['reported'] for r in group)} | {ratios[len(ratios) // 2]:.2f} | "
                 f"{errors[len(errors) // 2]:.2f} |")
    page.say("Per excitation (all parameters, reported intervals): " + ", ".join(
        f"{kind} {_pct(r['reported'] for r in rows if r['kind'] == kind)}"
        for kind in dict.fromkeys(r["kind"] for r in rows)) + ".")
    page.write()


if __name__ == "__main__":
    main()
