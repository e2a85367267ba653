"""The diagnosis on concealed effects: for every case of hdjoint.fmu.concealed_effects
(every effect ID, several at once, and controls), simulate the joint,
diagnose it against the nominal model, and print
  - the confusion table (effect named vs effect present),
  - false alarms on the controls,
  - held-out improvement of the named findings,
  - the time per case.
Run: python benchmarks/diagnosis_suite.py [--duration 30] [--markdown]

--independent: the same questions on an independent truth (hdjoint_truth,
not the project's own joint), several seeds, closure on a second recording;
see diagnosis_independent.py. Resumable and splittable:
  python benchmarks/diagnosis_suite.py --independent --seeds 3 [--cases NAME] [--which controls]
writes docs/results/diagnosis_independent.md (and .jsonl, the raw results).
"""
from __future__ import annotations

import argparse
import json
import pathlib
import time

from hdjoint.fmu.concealed_effects import CASES, nominal_for, record
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.diagnosis.effects import EFFECTS


def run_case(case, duration):
    rec = record(case, duration)
    start = time.perf_counter()
    _, doc = diagnose(rec, nominal_for(case))
    return doc, time.perf_counter() - start


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--duration", type=float, default=30.0, help="seconds per recording")
    ap.add_argument("--only", help="run only cases whose name contains this")
    ap.add_argument("--save", type=pathlib.Path, help="write each case's findings.json into this folder")
    ap.add_argument("--independent", action="store_true", help="run on the independent truth (hdjoint_truth)")
    ap.add_argument("--seeds", type=int, default=3, help="--independent: seeds 0..SEEDS-1")
    ap.add_argument("--first-seed", type=int, default=0, help="--independent: start at this seed")
    ap.add_argument("--cases", help="--independent: run only cases whose name contains this")
    ap.add_argument("--which", choices=("all", "effects", "controls"), default="all",
                    help="--independent: effect cases, controls, or both")
    ap.add_argument("--table-only", action="store_true", help="--independent: rebuild the table from the results")
    args = ap.parse_args()
    if args.independent:
        import diagnosis_independent as independent
        if not args.table_only:
            independent.run(list(range(args.first_seed, args.first_seed + args.seeds)), args.duration, args.cases,
                            args.which)
        print(independent.write_table(independent.load_results()))
        return
    rows = []
    for case in CASES:
        if args.only and args.only not in case.name:
            continue
        doc, seconds = run_case(case, args.duration)
        if args.save:
            args.save.mkdir(parents=True, exist_ok=True)
            slug = "".join(ch if ch.isalnum() else "_" for ch in case.name)[:40]
            (args.save / f"{slug}.json").write_text(json.dumps(doc, indent=1, default=str))
        named = [f["effect"] for f in doc["findings"]]
        hits = [e for e in case.present if e in named]
        extra = [e for e in named if e not in case.present]
        gains = {f["effect"]: (f["fit"]["holdout_rms_before"], f["fit"]["holdout_rms_after"]) for f in doc["findings"]}
        rows.append((case, doc["verdict"], named, hits, extra, gains, seconds))
        print(f"{case.name:<52} verdict {doc['verdict']:<16} named {named or '-'}  ({seconds:.1f} s)", flush=True)

    print("\n| case | present | named (confidence) | verdict | held-out RMS before -> after (N.m) | time (s) |")
    print("|---|---|---|---|---|---|")
    for case, verdict, named, hits, extra, gains, seconds in rows:
        present = ", ".join(case.present) or "nothing (control)"
        names = ", ".join(named) or "-"
        fit = "; ".join(f"{e}: {b:.3f} -> {a:.3f}" for e, (b, a) in gains.items()) or "-"
        print(f"| {case.name} | {present} | {names} | {verdict} | {fit} | {seconds:.1f} |")

    effects = list(EFFECTS)
    print("\nConfusion (rows: effect present, columns: effect named; single-effect cases):")
    print("| present \\ named | " + " | ".join(e.replace("_", " ") for e in effects) + " | none |")
    print("|---" * (len(effects) + 2) + "|")
    for case, verdict, named, *_ in rows:
        if len(case.present) != 1:
            continue
        cells = ["x" if e in named else "" for e in effects]
        print(f"| {case.present[0]} | " + " | ".join(cells) + f" | {'x' if not named else ''} |")
    controls = [r for r in rows if not r[0].present]
    single = [r for r in rows if len(r[0].present) == 1]
    multi = [r for r in rows if len(r[0].present) > 1]
    print(f"\nsingle-effect cases with the effect named first: "
          f"{sum(1 for r in single if r[2][:1] == list(r[0].present))}/{len(single)}; "
          f"named anywhere: {sum(1 for r in single if r[3])}/{len(single)}")
    print(f"false alarms on controls: {sum(1 for r in controls if r[2])}/{len(controls)} "
          f"(verdicts: {', '.join(r[1] for r in controls)})")
    for r in multi:
        print(f"multi-effect case '{r[0].name}': {len(r[3])}/{len(r[0].present)} named, {len(r[4])} extra")
    print(f"mean time per {args.duration:.0f} s recording: {sum(r[6] for r in rows) / len(rows):.1f} s")


if __name__ == "__main__":
    main()
