"""The joint-state filter (tau_hat) and its smoother (tau_smooth) against the
compliance model and the paper's UKF, on recordings the estimators never
fitted. Prints the README's table.

Each case simulates HarmonicDriveJoint.fmu under the PD position controller
of `hdjoint.fmu.experiments` on one excitation (the paper's sinusoid, a
multisine, slow moves with dwells, a chirp), with an external torque on the
link that neither controller nor estimators know (payload steps, contact
pushes), default or coarse encoders, and in some cases Bouc-Wen transmission
hysteresis that no estimator models. The estimators get the joint's
transmission parameters (the corrected model: wave generator loaded by the
transmitted torque, wg_load = 1), a link model that is a few percent off
(`LINK_MODEL_ERROR`) and the encoders' resolutions.

Tuning, the same for both filters: a grid search over their noise settings
(`tuning`) on a separate tuning recording per encoder set (two sines
at 0.2 and 0.7 Hz, other payload steps and contact pushes, other noise seed;
not a test recording), against its torque sensor. The compliance model has nothing to tune.

Coverage: the share of samples whose true torque lies within +-2 sigma of
each estimate (tau_ukf_std, tau_hat_std, tau_smooth_std); 95 % is honest.

"Model is wrong": the paper's experiment on a joint whose wave generator is
loaded by the transmitted torque while the nominal file keeps the paper's
approximation; estimated with the nominal file and with the file
`hdjoint diagnose` writes from another recording of the same joint.

"Goal 3": each case again with the joint's exact parameters (its link model,
and its hysteresis as the filter's Dahl law), what issue 39 asks of the filter itself.

The tables go to stdout and to docs/results/estimators.md (with date and machine).

Run: python benchmarks/joint_filter_cases.py [--quick]
"""
from __future__ import annotations

import argparse
import dataclasses
import math
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from hdjoint import _core
from hdjoint.diagnosis.effects.hysteresis import dahl_matching_bouc_wen
from hdjoint.fmu import experiments
from hdjoint.io import parameters
import tuning
from hdjoint.estimation.metrics import error_figures

ENCODERS = {
    "default": {"motor_counts": 4096.0, "link_counts": 524288.0},   # 1024 lines x4, 19 bit
    "coarse": {"motor_counts": 2048.0, "link_counts": 32768.0},     # 512 lines x4, 15 bit
}
HYSTERESIS = {"bw_A": 3e4, "bw_beta": 2e5, "bw_gamma": 1e5}  # Bouc-Wen, saturates at 0.1 N.m
# The link model the filter assumes, relative to the joint's.
LINK_MODEL_ERROR = {"Jl": 1.05, "Bl": 1.10, "mgl": 0.96}
ESTIMATES = ("tau_compliance", "tau_ukf", "tau_hat", "tau_smooth")
DEVIATIONS = {"tau_ukf": "tau_ukf_std", "tau_hat": "tau_hat_std", "tau_smooth": "tau_smooth_std"}
STD_NIS_TIME = 0.05  # s: the averaging time the coverage table shows beside the filters' own deviations
RESULTS = Path(__file__).resolve().parent.parent / "docs" / "results" / "estimators.md"


@dataclass
class Case:
    name: str
    experiment: str
    load: str            # "payload" or "contact"
    encoders: str        # key of ENCODERS
    hysteresis: bool = False
    seed: int = 11
    duration: float | None = None
    extra: dict = field(default_factory=dict)


CASES = [
    Case("sinusoid (paper), payload steps", "paper", "payload", "default"),
    Case("multisine, contact pushes", "multisine", "contact", "default", seed=12),
    Case("sweeps with dwells, payload steps", "sweep", "payload", "default", seed=13),
    Case("chirp, contact pushes", "chirp", "contact", "default", seed=14),
    Case("sinusoid (paper), payload, coarse encoders", "paper", "payload", "coarse", seed=15),
    Case("multisine, contact, coarse encoders", "multisine", "contact", "coarse", seed=16),
    Case("sweeps, payload, coarse, hysteresis", "sweep", "payload", "coarse", hysteresis=True, seed=17),
    Case("chirp, contact, hysteresis", "chirp", "contact", "default", hysteresis=True, seed=18),
]
LOADS = {"payload": experiments.payload_steps, "contact": experiments.contact_pushes}


def joint_parameters(encoders: str, hysteresis: bool) -> dict[str, float]:
    p = parameters.defaults()
    p.update(ENCODERS[encoders])
    if hysteresis:
        p.update(HYSTERESIS)
    return p


def estimator_parameters(encoders: str) -> dict[str, float]:
    joint = parameters.defaults()
    p = parameters.defaults()
    p["wg_load"] = 1.0  # the corrected model (the diagnosis's wave_generator_load)
    for name, factor in LINK_MODEL_ERROR.items():
        p[name] = joint[name] * factor
    p.update(ENCODERS[encoders])
    return p


def _tuning_reference(t):
    w1, w2 = 2 * math.pi * 0.2, 2 * math.pi * 0.7
    return 0.7 * np.sin(w1 * t) + 0.1 * np.sin(w2 * t), 0.7 * w1 * np.cos(w1 * t) + 0.1 * w2 * np.cos(w2 * t)


def tuning_recording(encoders: str, duration: float):
    experiments.EXPERIMENTS.setdefault("tuning", experiments.Experiment(
        "tuning", 20.0, _tuning_reference, "two sines (0.2, 0.7 Hz): the benchmark's tuning run"))
    load = lambda t: (experiments.payload_steps(t, levels=(0.0, -1.5, 2.0, 1.0), hold=5.0)
                      + experiments.contact_pushes(t, every=2.9, width=0.6, peak=2.0))
    return experiments.run("tuning", joint=joint_parameters(encoders, False), nominal=parameters.defaults(),
                           duration=duration, sensors=experiments.Sensors(seed=99), tau_ext=load)


def tuned_parameters(encoders: str, duration: float) -> tuple[dict[str, float], str]:
    rec = tuning_recording(encoders, duration)
    p = estimator_parameters(encoders)
    p, _ = tuning.tune(rec, p, tuning.PAPER_UKF_GRID, "tau_ukf")
    p, _ = tuning.tune(rec, p, tuning.JOINT_FILTER_GRID, "tau_hat")
    note = ", ".join(f"{k} = {p[k]:g}" for k in (*tuning.PAPER_UKF_GRID, *tuning.JOINT_FILTER_GRID))
    return p, note


def run_case(case: Case, params: dict[str, float], duration: float | None) -> dict[str, object]:
    rec = experiments.run(case.experiment, joint=joint_parameters(case.encoders, case.hysteresis),
                          nominal=parameters.defaults(), duration=duration or case.duration,
                          sensors=experiments.Sensors(seed=case.seed), tau_ext=LOADS[case.load])
    est = _core.run_estimator(parameters.for_estimator(params), rec.time, rec.i_m, rec.theta_m, rec.theta_l,
                              smooth=True)
    truth = rec.extra["tau_joint"]
    figures = {name: error_figures(est[name], truth) for name in ESTIMATES}
    cover = lambda e, name: 100.0 * float(np.mean(np.abs(e[name] - truth) <= 2.0 * e[DEVIATIONS[name]]))  # noqa: E731
    coverage = {name: cover(est, name) for name in DEVIATIONS}
    # The same estimates with the NIS-scaled deviations (std_nis_time, off by default).
    scaled = _core.run_estimator(parameters.for_estimator({**params, "std_nis_time": STD_NIS_TIME}), rec.time,
                                 rec.i_m, rec.theta_m, rec.theta_l)
    coverage.update({f"{name} (NIS-scaled)": cover(scaled, name) for name in ("tau_ukf", "tau_hat")})
    # What limits the filter: the same recording with the joint's exact link model, and with the
    # current the joint was driven by (no sensor noise; jsf_current_noise near 0).
    exact_link = {**params, **{k: joint_parameters(case.encoders, case.hysteresis)[k] for k in LINK_MODEL_ERROR}}
    # Goal 3 (issue 39): the filter with the joint's exact parameters, the hysteresis as its Dahl law.
    exact = {**exact_link, **(dahl_matching_bouc_wen(HYSTERESIS["bw_A"], HYSTERESIS["bw_beta"], HYSTERESIS["bw_gamma"])
                              if case.hysteresis else {})}
    e = _core.run_estimator(parameters.for_estimator(exact), rec.time, rec.i_m, rec.theta_m, rec.theta_l, smooth=True)
    exact_figures = {n: error_figures(e[n], truth) for n in ESTIMATES}
    exact_coverage = {name: cover(e, name) for name in ("tau_hat", "tau_smooth")}
    # What the exact set reaches when the current the joint was driven by is known: the current sensor's share.
    e = _core.run_estimator(parameters.for_estimator({**exact, "jsf_current_noise": 1e-4}), rec.time,
                            rec.extra["i_cmd"], rec.theta_m, rec.theta_l, smooth=True)
    exact_clean = {n: error_figures(e[n], truth) for n in ESTIMATES}
    known_load = load_known_limit(case, exact, duration) if case.encoders == "default" else None
    limits = {}
    for label, p, current in (("exact link model", exact_link, rec.i_m),
                              ("noise-free current", {**params, "jsf_current_noise": 1e-4}, rec.extra["i_cmd"])):
        e = _core.run_estimator(parameters.for_estimator(p), rec.time, current, rec.theta_m, rec.theta_l, smooth=True)
        limits[label] = {n: error_figures(e[n], truth) for n in ("tau_hat", "tau_smooth")}
    return {"case": case, "figures": figures, "coverage": coverage, "seconds": rec.duration, "limits": limits,
            "exact": {"figures": exact_figures, "coverage": exact_coverage, "noise-free current": exact_clean,
                      "load known": known_load},
            "rejected": int(np.sum(est["status"] == _core.STATUS_SAMPLE_REJECTED)), "samples": len(truth)}


# The load model of the information limit: a walk too slow to move the load in a run (its variance
# scales the Kalman gain, so 0 would leave the smoother's predicted covariance singular).
KNOWN_LOAD = {"jsf_q_load": 1e-5, "jsf_q_load_rate": 1e-5, "jsf_load_adapt_time": 0.0}


def load_known_limit(case: Case, exact: dict[str, float], duration: float | None) -> dict[str, object]:
    """The filter when the link's load is known: CASE run again without its external load, the filter with
    the exact set told the load is constant (KNOWN_LOAD). The motor current's noise and the encoders' counts
    remain, and on the slow excitations they are what binds: the Kalman smoother is the best estimator when
    the counts' error is taken as noise of its variance (the same runs with Gaussian readings in place of the
    counts score the same), so no estimator that is not told the load does better there. On the fast ones
    (multisine, chirp) the filter's trapezoidal step binds first: with the load known nothing absorbs its
    phase error at the torsional mode (a fourth-order step, measured and not adopted, lifts them by 3-11
    points and leaves the runs with an unknown load unchanged)."""
    rec = experiments.run(case.experiment, joint=joint_parameters(case.encoders, case.hysteresis),
                          nominal=parameters.defaults(), duration=duration or case.duration,
                          sensors=experiments.Sensors(seed=case.seed))
    e = _core.run_estimator(parameters.for_estimator({**exact, **KNOWN_LOAD}), rec.time, rec.i_m, rec.theta_m,
                            rec.theta_l, smooth=True)
    return {n: error_figures(e[n], rec.extra["tau_joint"]) for n in ESTIMATES}


def limits_table(results) -> list[str]:
    """Reduction below the compliance model of tau_hat / tau_smooth as run, with the exact link model, and
    with the noise-free current: what each would gain."""
    labels = ("exact link model", "noise-free current")
    lines = ["| case | as run | " + " | ".join(labels) + " |", "|" + "---|" * (len(labels) + 2)]
    for r in results:
        base = r["figures"]["tau_compliance"]
        cell = lambda f: " / ".join(f"{f[n].reduction_against(base):.0f} %" for n in ("tau_hat", "tau_smooth"))  # noqa: E731
        lines.append(f"| {r['case'].name} | {cell(r['figures'])} | " +
                     " | ".join(cell(r["limits"][label]) for label in labels) + " |")
    return lines


def reduction_table(results) -> tuple[list[str], dict[str, float]]:
    lines = ["| case | " + " | ".join(f"{n} RMS / max (N.m)" for n in ESTIMATES) +
             " | reduction vs compliance: UKF / tau_hat / tau_smooth |",
             "|" + "---|" * (len(ESTIMATES) + 2)]
    reductions = {n: [] for n in ESTIMATES[1:]}
    for r in results:
        f = r["figures"]
        base = f["tau_compliance"]
        cells = [f"{f[n].rms:.3f} / {f[n].max:.3f}" for n in ESTIMATES]
        for n in ESTIMATES[1:]:
            reductions[n].append(f[n].reduction_against(base))
        lines.append(f"| {r['case'].name} | " + " | ".join(cells) + " | " +
                     " / ".join(f"{reductions[n][-1]:.0f} %" for n in ESTIMATES[1:]) + " |")
    means = {n: float(np.mean(v)) for n, v in reductions.items()}
    rms_mean = {n: float(np.mean([r["figures"][n].rms for r in results])) for n in ESTIMATES}
    lines.append("| **average** | " + " | ".join(f"{rms_mean[n]:.3f}" for n in ESTIMATES) + " | " +
                 " / ".join(f"**{means[n]:.0f} %**" for n in ESTIMATES[1:]) + " |")
    return lines, means


def exact_parameters_table(results) -> tuple[list[str], str]:
    """Goal 3 (issue 39): with the joint's exact parameters, each filter's reduction below the compliance model,
    beside what it reaches with the noise-free current, and its +-2 sigma coverage per case. The reduction
    goals hold for fine encoders (the issue's condition): the verdict judges those cases, each one."""
    lines = ["| case | tau_compliance RMS (N.m) | reduction: tau_hat / tau_smooth | with the noise-free current | "
             "with the load known | coverage: tau_hat / tau_smooth |", "|---|---|---|---|---|---|"]
    fine = {"tau_hat": [], "tau_smooth": []}
    limit = {"tau_hat": [], "tau_smooth": []}
    cuts = lambda f: {n: f[n].reduction_against(f["tau_compliance"]) for n in fine}  # noqa: E731
    cells = lambda cut: " / ".join(f"{cut[n]:.0f} %" for n in fine)  # noqa: E731
    outside, worse = [], []
    for r in results:
        f, c, clean = r["exact"]["figures"], r["exact"]["coverage"], r["exact"]["noise-free current"]
        cut, known = cuts(f), r["exact"]["load known"]
        if r["case"].encoders == "default":
            for n in fine:
                fine[n].append(cut[n])
                limit[n].append(cuts(known)[n])
        outside += [f"{r['case'].name} ({n} {c[n]:.1f} %)" for n in fine if not 93.0 <= c[n] <= 97.0]
        if f["tau_smooth"].rms > f["tau_hat"].rms:
            worse.append(r["case"].name)
        lines.append(f"| {r['case'].name} | {f['tau_compliance'].rms:.3f} | {cells(cut)} | {cells(cuts(clean))} | "
                     f"{cells(cuts(known)) if known else '-'} | {c['tau_hat']:.1f} % / {c['tau_smooth']:.1f} % |")
    met = {n: sum(v >= goal for v in fine[n]) for n, goal in (("tau_hat", 70.0), ("tau_smooth", 80.0))}
    span = lambda v: f"{min(v):.0f}-{max(v):.0f} %"  # noqa: E731
    verdict = (f"With exact parameters and fine encoders ({len(fine['tau_hat'])} cases): tau_hat "
               f"{span(fine['tau_hat'])} below the compliance model, at least 70 % on {met['tau_hat']}; tau_smooth "
               f"{span(fine['tau_smooth'])}, at least 80 % on {met['tau_smooth']}. With the load known (the run "
               "without its external load, the filter told the load is constant; where this is below the figure as "
               "run, the filter's trapezoidal step binds before the sensors do: load_known_limit): tau_hat "
               f"{span(limit['tau_hat'])}, tau_smooth {span(limit['tau_smooth'])}. tau_smooth worse than tau_hat on: "
               f"{', '.join(worse) or 'no case'}; coverage outside 93-97 %: {'; '.join(outside) or 'none'}.")
    return lines, verdict


def coverage_table(results) -> list[str]:
    names = ("tau_ukf", "tau_ukf (NIS-scaled)", "tau_hat", "tau_hat (NIS-scaled)", "tau_smooth")
    lines = ["| case | " + " | ".join(names) + " | samples rejected as outliers (of all) |", "|" + "---|" * (len(names) + 2)]
    for r in results:
        c = r["coverage"]
        lines.append(f"| {r['case'].name} | " + " | ".join(f"{c[n]:.1f} %" for n in names) +
                     f" | {r['rejected']} of {r['samples']} |")
    return lines


def model_is_wrong(duration: float) -> tuple[list[str], dict[str, dict]]:
    """The paper's approximation of the wave generator load against a joint that
    does not follow it: estimates with the nominal file and with the diagnosed one
    (the table's lines, and each file's error figures by estimate)."""
    from hdjoint.app import cli
    from hdjoint.fmu.concealed_effects import CASES, nominal_for, record
    from hdjoint.io.recording import write_recording
    case = next(c for c in CASES if c.present == ("wave_generator_load",))
    bench, run = record(case, duration=duration), record(dataclasses.replace(case, seed=23), duration=duration)
    truth = run.extra["tau_joint"]
    lines = ["| parameter file | " + " | ".join(f"{n} RMS (N.m)" for n in ESTIMATES) + " |",
             "|" + "---|" * (len(ESTIMATES) + 1)]
    figures = {}
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        write_recording(tmp / "bench.csv", bench)
        parameters.save(tmp / "nominal.json", nominal_for(case))
        if cli.main(["diagnose", str(tmp / "bench.csv"), "--params", str(tmp / "nominal.json"),
                     "--out", str(tmp / "d")]) != 0:
            raise RuntimeError("the diagnosis failed on the bench recording")
        for label, path in (("nominal (paper's approximation)", tmp / "nominal.json"),
                            ("after hdjoint diagnose", tmp / "d" / "params.json")):
            p = parameters.for_estimator(parameters.load(path))
            est = _core.run_estimator(p, run.time, run.i_m, run.theta_m, run.theta_l, smooth=True)
            figures[label] = {n: error_figures(est[n], truth) for n in ESTIMATES}
            lines.append(f"| {label} | " + " | ".join(f"{figures[label][n].rms:.3f}" for n in ESTIMATES) + " |")
    return lines, figures


def write_results(sections: list[tuple[str, list[str]]], notes: list[str]) -> None:
    import stamp
    text = ["# Estimator benchmark (benchmarks/joint_filter_cases.py)", "",
            stamp.generated_by("python benchmarks/joint_filter_cases.py"), ""] + notes + [""]
    for title, lines in sections:
        text += [f"## {title}", ""] + lines + [""]
    RESULTS.parent.mkdir(parents=True, exist_ok=True)
    RESULTS.write_text("\n".join(text))


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="10 s per case and tuning run (a smoke run)")
    args = ap.parse_args(argv)
    duration = 10.0 if args.quick else None
    start = time.perf_counter()
    tuned, notes = {}, []
    for enc in ENCODERS:
        tuned[enc], note = tuned_parameters(enc, 10.0 if args.quick else 20.0)
        notes.append(f"Tuned on the tuning recording ({enc} encoders): {note}.")
        print(notes[-1])
    results = []
    for case in CASES:
        results.append(run_case(case, tuned[case.encoders], duration))
        print(f"  done: {case.name} ({time.perf_counter() - start:.0f} s)", flush=True)
    reduction, means = reduction_table(results)
    coverage = coverage_table(results)
    wrong, wrong_figures = model_is_wrong(10.0 if args.quick else 20.0)
    sections = [("RMS error against the true joint torque, and reduction below the compliance model", reduction),
                (f"Coverage: true torque within +-2 sigma (honest: 95 %); NIS-scaled: std_nis_time = {STD_NIS_TIME} s",
                 coverage),
                ("Model is wrong: nominal file against the diagnosed one", wrong),
                ("What limits the joint-state filter: reduction of tau_hat / tau_smooth below the compliance model "
                 "as run, with the joint's exact link model, with the noise-free current", limits_table(results))]
    exact_lines, exact_verdict = exact_parameters_table(results)
    sections.append(("Goal 3 (issue 39): the filter with the joint's exact parameters (link model; the hysteresis as "
                     "the filter's Dahl law with the loop's first slope and height)", [exact_verdict, ""] + exact_lines))
    for title, lines in sections:
        print(f"\n{title}\n" + "\n".join(lines))
    summary = (f"average RMS reduction vs compliance: paper UKF {means['tau_ukf']:.1f} %, tau_hat "
               f"{means['tau_hat']:.1f} %, tau_smooth {means['tau_smooth']:.1f} %  "
               f"({time.perf_counter() - start:.0f} s{', --quick' if args.quick else ''})")
    worse = [r["case"].name for r in results if r["figures"]["tau_smooth"].rms > r["figures"]["tau_hat"].rms]
    worse += [f"model is wrong, {label}" for label, f in wrong_figures.items() if f["tau_smooth"].rms > f["tau_hat"].rms]
    outside = [f"{r['case'].name} ({n} {r['coverage'][n]:.1f} %)" for r in results for n in ("tau_hat", "tau_smooth")
               if not 93.0 <= r["coverage"][n] <= 97.0]
    checks = (f"tau_smooth worse than tau_hat on: {', '.join(worse) or 'no case'}. "
              f"+-2 sigma coverage outside 93-97 %: {'; '.join(outside) or 'none'}.")
    print("\n" + summary + "\n" + checks)
    write_results(sections, notes + [summary, "", checks])


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()
