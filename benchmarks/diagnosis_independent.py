"""The diagnosis on an independent truth (hdjoint_truth: Python, not the
project's C++ joint, with its model form drawn per seed): every effect ID
concealed one, two or three at a time, controls on every excitation kind,
and closure: the corrected params.json used as the nominal set for a second
recording of the same joint with another excitation.

Each run goes through `hdjoint diagnose` (jobs.diagnose_to_directory) on CSV
files. Results are appended to a JSON-lines file, one line per case and
seed, so the run can be split (--cases, --seeds, --controls/--effects) and
resumed; the Markdown table is rebuilt from all lines every time.
Called by diagnosis_suite.py --independent."""
from __future__ import annotations

import json
import multiprocessing
import tempfile
import time
from pathlib import Path

import stamp
from hdjoint.io import parameters
from hdjoint.diagnosis.effects import EFFECTS
from hdjoint.jobs.diagnose import diagnose_to_directory
from hdjoint.io.recording import write_recording
from hdjoint_truth.cases import CONTROL_CASES, EFFECT_CASES, TruthCase, draw, record

ROOT = Path(__file__).resolve().parents[1]
RESULTS = ROOT / "docs" / "results" / "diagnosis_independent.jsonl"
TABLE = ROOT / "docs" / "results" / "diagnosis_independent.md"
# effect_detectability.py's rows: each miss retested from the truth's own values.
ORACLE = ROOT / "docs" / "results" / "effect_detectability.jsonl"
GOALS = {"false_alarms": 0.05, "named_first": 0.90, "closure": 0.90}
FIRST_ROUND_KEYS = ("effect", "held_out_gain", "z", "p_value", "delta_bic", "folds_improved", "worst_channel_ratio",
                    "degenerate", "z_against_null", "accepted")


def _named(finding: dict) -> set[str]:
    """Effects a finding names: itself, or every member of a look-alike set."""
    return {finding["effect"]} | {a["effect"] for a in finding.get("alternatives") or []}


ANGLES = {"m": "theta_m", "l": "theta_l"}


def truth_orders(joint) -> set[tuple[str, float]]:
    """The (angle, order) ripples the truth has that the nominal model lacks:
    the kinematic error's extra orders and cogging."""
    orders = {(ANGLES[a], k) for a, k, _, _ in joint.form.extra_kinematic}
    if joint.truth.get("cog_a") or joint.truth.get("cog_b"):
        orders.add(("theta_m", joint.truth["cog_order"]))
    return orders


def _orders(finding: dict) -> list[list]:
    """The (angle, order) terms an added finding fitted, from its slots' <slot>_order parameters."""
    effect, fitted = EFFECTS.get(finding["effect"]), finding.get("parameters") or {}
    return sorted([angle, fitted[f"{slot}_order"]] for slot, angle in (effect.slots if effect else ())
                  if f"{slot}_order" in fitted)


def summary(doc: dict) -> dict:
    return {"verdict": doc["verdict"], "seconds": doc.get("seconds"),
            "findings": [{"effect": f["effect"], "kind": f.get("kind", "added"), "named": sorted(_named(f)),
                          "p_value": f.get("p_value"), "orders": _orders(f)} for f in doc["findings"]],
            "unexplained": len(doc.get("unexplained") or []),
            "proposed_terms": [t.get("terms") for t in doc.get("proposed_terms") or []],
            # What the first round of tests saw, with every input of the acceptance
            # rule (Hypothesis.accepted), so other rules can be compared offline.
            "first_round": [{k: h[k] for k in FIRST_ROUND_KEYS if k in h}
                            for h in (doc.get("hypotheses_tested") or [[]])[0]],
            "cannot_tell": [c["effect"] for c in doc.get("cannot_tell") or [] if "effect" in c]}


def diagnose_csv(rec, params_path: Path, out: Path) -> tuple[dict, float]:
    csv = out.with_suffix(".csv")
    write_recording(csv, rec)
    start = time.perf_counter()
    doc = diagnose_to_directory(str(csv), str(params_path), str(out))
    return doc, time.perf_counter() - start


def run_case(case: TruthCase, seed: int, duration: float) -> dict:
    joint = draw(case, seed, duration)
    row = {"case": case.name, "present": list(case.present), "seed": seed, "duration": duration,
           "form": joint.description, "commit": stamp.commit(), "engine": stamp.engine(), "runs": []}
    with tempfile.TemporaryDirectory(prefix="hdjoint-independent-") as tmp:
        tmp = Path(tmp)
        nominal = tmp / "nominal.json"
        parameters.save(nominal, joint.nominal)
        for index in range(len(joint.setups)):
            start = time.perf_counter()
            rec = record(joint, index)
            simulated = time.perf_counter() - start
            # A control's second recording is another control run; an effect
            # case's is diagnosed against the first one's corrected set (closure).
            params = nominal if not case.present or index == 0 else tmp / "run0" / "params.json"
            doc, wall = diagnose_csv(rec, params, tmp / f"run{index}")
            row["runs"].append(dict(summary(doc), excitation=joint.setups[index].excitation,
                                    simulate_seconds=round(simulated, 1), wall_seconds=round(wall, 1),
                                    nominal=("nominal" if params == nominal else "corrected by run 0")))
    return row


def load_results(path: Path = RESULTS, key: tuple[str, ...] = ("case", "seed", "duration")) -> list[dict]:
    """Every row of a JSON-lines results file, one per `key`: the first one
    where parts run side by side did one twice."""
    if not path.exists():
        return []
    rows = {}
    for line in path.read_text().splitlines():
        if line.strip():
            row = json.loads(line)
            rows.setdefault(tuple(row[k] for k in key), row)
    return list(rows.values())


def run_pending(jobs: list[tuple], work, path: Path, key: tuple[str, ...], workers: int, describe) -> list[dict]:
    """Run `work` on each job (a tuple of the row's `key` values) not yet in
    `path`, on `workers` processes, appending each row as it comes (so a run
    can be stopped and resumed); returns every row."""
    done = {tuple(r[k] for k in key) for r in load_results(path, key)}
    todo = [job for job in jobs if tuple(job) not in done]
    with multiprocessing.get_context("fork").Pool(workers) as pool:
        for row in pool.imap_unordered(work, todo):
            with path.open("a") as f:
                f.write(json.dumps(row) + "\n")
            print(describe(row), flush=True)
    return load_results(path, key)


def run(seeds: list[int], duration: float, only: str | None, which: str, path: Path = RESULTS) -> None:
    cases = (EFFECT_CASES if which in ("all", "effects") else []) + \
        (CONTROL_CASES if which in ("all", "controls") else [])
    path.parent.mkdir(parents=True, exist_ok=True)
    for seed in seeds:
        for case in cases:
            done = {(r["case"], r["seed"], r["duration"]) for r in load_results(path)}  # other parts may run too
            if only and only not in case.name or (case.name, seed, duration) in done:
                continue
            row = run_case(case, seed, duration)
            with path.open("a") as f:
                f.write(json.dumps(row) + "\n")
            first = row["runs"][0]
            print(f"seed {seed} {case.name:<52} {first['verdict']:<16} "
                  f"{[f['effect'] for f in first['findings']] or '-'}  ({first['wall_seconds']} s)", flush=True)
            write_table(load_results(path))


def _engines(rows: list[dict]) -> str:
    """Which commits' engines diagnosed the rows: the last commit that changed the engine
    (rows before 2026-11-24 02:00 UTC kept HEAD instead; before 2026-11-23 17:30 UTC, nothing)."""
    by_commit: dict[str, list[str]] = {}
    for r in rows:
        kind = "controls" if not r["present"] else "effects"
        engine = r.get("engine") or r.get("commit", "an earlier, unrecorded commit")
        by_commit.setdefault(engine, []).append(f"{kind} s{r['seed']}")
    return "; ".join(f"{c} ({', '.join(sorted(set(w)))})" for c, w in by_commit.items())


def _pct(hits: int, total: int) -> str:
    return f"{hits}/{total} ({100 * hits / total:.0f} %)" if total else "-"


def _first_said(row: dict) -> str:
    """What the first recording's diagnosis said first, with its excitation, and
    which missing effects it said it cannot tell (rows written before 2026-11-23 lack that)."""
    run = row["runs"][0]
    first = run["findings"][0] if run["findings"] else None
    orders = ", ".join(f"{a} {k:g}" for a, k in first.get("orders") or []) if first else ""
    said = f"{first['effect']} ({first['kind']}{'; ' + orders if orders else ''})" if first else run["verdict"]
    missed = [e for e in run.get("cannot_tell", []) if e in row["present"]]
    return f"s{row['seed']} {run['excitation']}: {said}" + (f", cannot tell {', '.join(missed)}" if missed else "")


def _orders_right(row: dict) -> bool:
    """The first finding names only orders the truth has (none: eq. (7)'s own, resized)."""
    first = row["runs"][0]["findings"][0]
    case = next(c for c in EFFECT_CASES if c.name == row["case"])
    truth = truth_orders(draw(case, row["seed"], row["duration"]))
    return all((a, k) in truth for a, k in first["orders"])


def load_oracle(path: Path = ORACLE) -> dict[tuple, str]:
    """(case, seed, effect) -> the oracle's verdict ("detectable", "not detectable", ...)."""
    if not path.exists():
        return {}
    out = {}
    for line in path.read_text().splitlines():
        r = json.loads(line)
        effect = r.get("effect") or next(c.present[0] for c in EFFECT_CASES if c.name == r["case"])
        out[(r["case"], r["seed"], effect)] = r["verdict"]
    return out


def _oracle_row(misses: list[dict], oracle: dict[tuple, str]) -> str:
    """How many missed single effects the truth's own values could not show either."""
    verdicts = [oracle.get((r["case"], r["seed"], r["present"][0])) for r in misses]
    hidden = sum(v == "not detectable" for v in verdicts)
    untested = sum(v is None for v in verdicts)
    return (f"| missed single effects that the diagnosis's test, started at the truth's own values, cannot show "
            f"either (effect_detectability.md) | {_pct(hidden, len(misses))}"
            + (f"; {untested} not retested" if untested else "") + " | - |")


def _oracle_multi_row(multi: list[dict], oracle: dict[tuple, str]) -> str:
    """How many cases of several effects had each effect named, or below what
    the recording shows beside the others (the oracle cannot show it either)."""
    def accounted(r):
        named = {e for f in r["runs"][0]["findings"] for e in f["named"]}
        return all(e in named or oracle.get((r["case"], r["seed"], e)) == "not detectable" for e in r["present"])
    return (f"| several effects: each one named, or one the diagnosis's test beside the others, started at the "
            f"truth's own values, cannot show either (effect_detectability.md) | "
            f"{_pct(sum(map(accounted, multi)), len(multi))} | - |")


def write_table(rows: list[dict], path: Path = TABLE, oracle: dict[tuple, str] | None = None) -> str:
    controls = [run for r in rows if not r["present"] for run in r["runs"]]
    single = [r for r in rows if len(r["present"]) == 1]
    multi = [r for r in rows if len(r["present"]) > 1]
    first_named = lambda r: bool(r["runs"][0]["findings"]) and r["present"][0] in r["runs"][0]["findings"][0]["named"]  # noqa: E731
    named_all = lambda r: set(r["present"]) <= {e for f in r["runs"][0]["findings"] for e in f["named"]}  # noqa: E731
    accounted = lambda r: set(r["present"]) <= ({e for f in r["runs"][0]["findings"] for e in f["named"]}  # noqa: E731
                                              | set(r["runs"][0].get("cannot_tell", [])))
    closure_rows = [r for r in rows if r["present"] and len(r["runs"]) > 1]
    closed = lambda r: r["runs"][1]["verdict"] == "consistent"  # noqa: E731
    # Closure means something only when the first diagnosis modelled what was missing.
    closed_named = [r for r in closure_rows if named_all(r) and closed(r)]
    missed = [r for r in single if not first_named(r) and "cannot_tell" in r["runs"][0]]
    oracle = load_oracle() if oracle is None else oracle
    rippled = [r for r in single if EFFECTS[r["present"][0]].slots and first_named(r)]
    unrecorded = [r for r in rippled if "orders" not in r["runs"][0]["findings"][0]]
    rippled = [r for r in rippled if r not in unrecorded]
    orders_right = [r for r in rippled if _orders_right(r)]
    alarms = sum(run["verdict"] != "consistent" for run in controls)
    told = [run for run in controls if "cannot_tell" in run]  # runs from before 2026-11-23 did not keep it
    times = [run["seconds"] for r in rows for run in r["runs"] if run.get("seconds") is not None]
    sims = [run["simulate_seconds"] for r in rows for run in r["runs"]]
    seeds = sorted({r["seed"] for r in rows})
    durations = sorted({r["duration"] for r in rows})
    lines = [
        "# Diagnosis on an independent truth",
        "",
        stamp.generated_by("python benchmarks/diagnosis_suite.py --independent"),
        f"The rows were diagnosed by the engine at: {_engines(rows)}.",
        f"Seeds {seeds}, recordings of {', '.join(f'{d:g}' for d in durations)} s. "
        "How the truth is built: docs/benchmarks.md. Raw results: diagnosis_independent.jsonl.",
        "",
        "| goal (issue 10) | measured | goal |",
        "|---|---|---|",
        f"| false alarms on controls (verdict not `consistent`) | {_pct(alarms, len(controls))} | "
        f"<= {100 * GOALS['false_alarms']:.0f} % over >= 40 runs |",
        f"| single effect named first (added, resized or in a look-alike set) | "
        f"{_pct(sum(map(first_named, single)), len(single))} | >= {100 * GOALS['named_first']:.0f} % |",
        _oracle_row([r for r in single if not first_named(r)], oracle),
        f"| of those with ripples (kinematic error, cogging), named at the truth's orders only | "
        f"{_pct(len(orders_right), len(rippled))}"
        + (f" ({len(unrecorded)} more in rows written before orders were kept)" if unrecorded else "") + " | - |",
        f"| several effects: all named | {_pct(sum(map(named_all, multi)), len(multi))} | all |",
        f"| several effects: each one named, or said `cannot_tell` (too small for this recording) | "
        f"{_pct(sum(map(accounted, multi)), len(multi))} | - |",
        _oracle_multi_row(multi, oracle),
        f"| closure: corrected set `consistent` on the second recording | "
        f"{_pct(sum(map(closed, closure_rows)), len(closure_rows))}; with every effect named on the first: "
        f"{_pct(len(closed_named), len(closure_rows))} | >= {100 * GOALS['closure']:.0f} % |",
        f"| missed single effects the diagnosis said it cannot tell (`cannot_tell`) | "
        f"{_pct(sum(r['present'][0] in r['runs'][0].get('cannot_tell', []) for r in missed), len(missed))} | - |",
        f"| controls where `cannot_tell` names an effect (a `consistent` verdict's caveat) | "
        f"{_pct(sum(bool(run['cannot_tell']) for run in told), len(told))} | - |",
        f"| diagnosis wall time per recording, under the load of parallel runs (mean / max) | "
        f"{(sum(times) / len(times)) if times else 0:.1f} / {max(times, default=0):.1f} s | <= 20 s CPU per 58 s (measured alone: diagnosis_speed.md) |",
        f"| truth simulation per recording (mean / max) | "
        f"{(sum(sims) / len(sims)) if sims else 0:.1f} / {max(sims, default=0):.1f} s | <= 10 s per 30 s |",
        "",
        "## Per effect (first recording against the nominal set; closure on the second)",
        "",
        "| case | runs | named first | named anywhere | closure | what was named first (per seed) |",
        "|---|---|---|---|---|---|",
    ]
    for name in dict.fromkeys(r["case"] for r in rows if r["present"]):
        group = [r for r in rows if r["case"] == name]
        firsts = "; ".join(_first_said(r) for r in group)
        first = sum(map(first_named, group)) if len(group[0]["present"]) == 1 else "-"
        lines.append(f"| {name} | {len(group)} | {first} | {sum(map(named_all, group))} | "
                     f"{sum(map(closed, [r for r in group if len(r['runs']) > 1]))} | {firsts} |")
    lines += ["", "## Controls (nothing missing), per excitation", "",
              "| excitation | runs | false alarms | verdicts and first findings |", "|---|---|---|---|"]
    by_kind: dict[str, list] = {}
    for r in rows:
        if not r["present"]:
            for run in r["runs"]:
                by_kind.setdefault(run["excitation"], []).append(run)
    for kind, runs in by_kind.items():
        said = "; ".join(run["verdict"] + (f" ({run['findings'][0]['effect']})" if run["findings"] else "")
                         for run in runs if run["verdict"] != "consistent") or "all consistent"
        lines.append(f"| {kind} | {len(runs)} | {sum(run['verdict'] != 'consistent' for run in runs)} | {said} |")
    text = "\n".join(lines) + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return text
