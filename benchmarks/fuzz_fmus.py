"""The long FMI call-sequence fuzz run over the three FMUs (the CI test runs
a few hundred sequences; this runs --sequences per FMU, 10,000 by default),
with the first finding of each kind minimised to a reproducer. Writes the
figures to docs/results/fuzz.md (date, machine, FMU build) and each FMU's
record, with the reproducers, to docs/results/fuzz_<FMU>.json. One process
per FMU may run in parallel (--fmu NAME); the last one's report has them all.

Run: python benchmarks/fuzz_fmus.py [--sequences N] [--timeout CPU_SECONDS] [--fmu NAME ...]

--wild N instead feeds both estimators N wild-reading scenarios on each engine
(batch path, FMI 2.0, FMI 3.0; tests/fuzz/wild_readings.py) and prints the findings.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))

from fmi_fuzzer import CATEGORIES, FMU_NAMES, Campaign, summarise  # noqa: E402
import stamp
from hdjoint.fmu.shipped import fmu_path  # noqa: E402


def fuzz_one(campaign: Campaign, name: str, sequences: int, timeout: float, out: Path) -> None:
    """Run NAME's sequences, saving the figures to OUT/fuzz_NAME.json after every block (a stopped run
    keeps what it did), then minimise the first finding of each kind."""
    start, outcomes, first = time.monotonic(), [], {}
    record = out / f"fuzz_{name}.json"
    for block in range(0, sequences, 500):
        for o in campaign.run(name, range(block, min(block + 500, sequences)), timeout):
            outcomes.append(o)
            for category in {f[0] for f in o.findings}:
                first.setdefault(category, o)
        summary = summarise(outcomes)
        summary.update(seconds=time.monotonic() - start, timeout=timeout, reproducers={
            c: {"seed": o.seed, "calls": o.ops, "finding": next(f[2] for f in o.findings if f[0] == c),
                "minimised": False} for c, o in first.items()})
        record.write_text(json.dumps(summary, indent=1) + "\n")
        print(f"{name}: {len(outcomes)} sequences, {summary['seconds']:.0f} s", file=sys.stderr, flush=True)
    for category, o in first.items():
        ops = campaign.minimise(name, o.ops, category, timeout)
        detail = next((f[2] for f in campaign.replay(name, ops, timeout).findings if f[0] == category), None)
        if detail is None:  # it did not happen again (a hang that was the machine's load): keep the sequence as found
            summary["reproducers"][category]["finding"] += " (not reproduced on replay)"
            continue
        summary["reproducers"][category] = {"seed": o.seed, "calls": ops, "finding": detail, "minimised": True}
    record.write_text(json.dumps(summary, indent=1) + "\n")


def write_report(out: Path) -> str:
    """docs/results/fuzz.md from the fuzz_*.json records present."""
    build = {n: hashlib.sha256(fmu_path(n).read_bytes()).hexdigest()[:12] for n in FMU_NAMES}
    records = {n: json.loads((out / f"fuzz_{n}.json").read_text()) for n in FMU_NAMES
               if (out / f"fuzz_{n}.json").is_file()}
    lines = [
        "# FMI call-sequence fuzzing (benchmarks/fuzz_fmus.py)",
        "",
        stamp.generated_by("python benchmarks/fuzz_fmus.py") + " Each sequence in a forked child; FMU builds (sha256): "
        + ", ".join(f"{n} {h}" for n, h in build.items()) + ".",
        "",
        "Sequences with at least one finding / findings in all:",
        "",
        "| FMU | sequences | calls | " + " | ".join(CATEGORIES) + " | hang budget (CPU s) | seconds |",
        "|---|---:|---:|" + "---:|" * len(CATEGORIES) + "---:|---:|",
    ]
    for name, s in records.items():
        cells = " | ".join(f"{s['sequences_with'][c]} / {s['findings'][c]}" for c in CATEGORIES)
        lines.append(f"| {name} | {s['sequences']} | {s['calls']} | {cells} | {s['timeout']} | {s['seconds']:.0f} |")
    lines += ["", "First finding of each kind (call lists in fuzz_<FMU>.json; minimised where marked):", ""]
    for name, s in records.items():
        lines += [f"- **{name}, {c}** ({len(r['calls'])} calls{', minimised' if r['minimised'] else ''}, "
                  f"seed {r['seed']}): {r['finding']}" for c, r in s["reproducers"].items()]
    if not any(s["reproducers"] for s in records.values()):
        lines.append("None: no finding of any kind.")
    text = "\n".join(lines) + "\n"
    (out / "fuzz.md").write_text(text)
    return text


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sequences", type=int, default=10_000, help="sequences per FMU (default 10,000)")
    ap.add_argument("--timeout", type=float, default=1.0,
                    help="CPU seconds a sequence may use before it is a hang (default 1; the wall-clock "
                         "backstop is fmi_fuzzer.BACKSTOP_FACTOR times it)")
    ap.add_argument("--fmu", nargs="+", default=list(FMU_NAMES), choices=FMU_NAMES)
    ap.add_argument("--report-only", action="store_true", help="only rewrite fuzz.md from the saved records")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    ap.add_argument("--wild", type=int, metavar="N", help="run N wild-reading scenarios per engine instead")
    args = ap.parse_args(argv)
    if args.wild:
        from wild_readings import campaign as wild_campaign
        outcomes = wild_campaign(range(args.wild))
        found = [f"{o.engine}: {o.scenario.describe()}: {f}" for o in outcomes for f in o.findings]
        print("\n".join(found) or f"{len(outcomes)} wild-reading runs, no finding")
        return 1 if found else 0
    args.out.mkdir(parents=True, exist_ok=True)
    if not args.report_only:
        with tempfile.TemporaryDirectory() as work:
            campaign = Campaign.load([fmu_path(n) for n in FMU_NAMES], work)
            for name in args.fmu:
                fuzz_one(campaign, name, args.sequences, args.timeout, args.out)
    print(write_report(args.out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
