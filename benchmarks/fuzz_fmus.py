"""The long FMI call-sequence fuzz run over the three FMUs (the CI test runs
a few hundred sequences; this runs --sequences per FMU, 10,000 by default),
with the first finding of each kind minimised to a reproducer. Writes the
figures to docs/results/fuzz.md (date, machine, FMU build) and the
reproducers to docs/results/fuzz_reproducers.json.

Run: python benchmarks/fuzz_fmus.py [--sequences N] [--timeout S] [--fmu NAME ...]
"""
from __future__ import annotations

import argparse
import datetime
import hashlib
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "tests" / "fuzz"))

from fmi_fuzzer import CATEGORIES, FMU_NAMES, Campaign, summarise  # noqa: E402
from hdjoint.fmus import fmu_path  # noqa: E402


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sequences", type=int, default=10_000, help="sequences per FMU (default 10,000)")
    ap.add_argument("--timeout", type=float, default=1.5, help="seconds a sequence may take before it is a hang")
    ap.add_argument("--fmu", nargs="+", default=list(FMU_NAMES), choices=FMU_NAMES)
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    args = ap.parse_args(argv)

    with tempfile.TemporaryDirectory() as work:
        campaign = Campaign.load([fmu_path(n) for n in FMU_NAMES], work)
        rows, reproducers = [], {}
        for name in args.fmu:
            start = time.monotonic()
            outcomes = []
            for first in range(0, args.sequences, 500):
                outcomes += campaign.run(name, range(first, min(first + 500, args.sequences)), args.timeout)
                print(f"{name}: {len(outcomes)} sequences, {time.monotonic() - start:.0f} s", file=sys.stderr,
                      flush=True)
            summary = summarise(outcomes)
            summary["seconds"] = time.monotonic() - start
            rows.append((name, summary))
            for category in CATEGORIES:
                hit = next((o for o in outcomes if any(f[0] == category for f in o.findings)), None)
                if hit is not None:
                    ops = campaign.minimise(name, hit.ops, category, args.timeout)
                    detail = next(f[2] for f in campaign.replay(name, ops, args.timeout).findings
                                  if f[0] == category)
                    reproducers[f"{name}: {category}"] = {"seed": hit.seed, "calls": ops, "finding": detail}

    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "fuzz_reproducers.json").write_text(json.dumps(reproducers, indent=1) + "\n")
    build = {n: hashlib.sha256(fmu_path(n).read_bytes()).hexdigest()[:12] for n in FMU_NAMES}
    lines = [
        "# FMI call-sequence fuzzing (benchmarks/fuzz_fmus.py)",
        "",
        f"{datetime.datetime.now(datetime.timezone.utc):%Y-%m-%d %H:%M} UTC, "
        f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}; "
        f"{args.sequences} sequences per FMU, each in a forked child, hang budget {args.timeout} s; "
        "FMU builds (sha256): " + ", ".join(f"{n} {h}" for n, h in build.items()) + ".",
        "",
        "Findings (sequences with at least one / findings in all):",
        "",
        "| FMU | sequences | calls | " + " | ".join(CATEGORIES) + " | seconds |",
        "|---|---:|---:|" + "---:|" * len(CATEGORIES) + "---:|",
    ]
    for name, s in rows:
        cells = " | ".join(f"{s['sequences_with'][c]} / {s['findings'][c]}" for c in CATEGORIES)
        lines.append(f"| {name} | {s['sequences']} | {s['calls']} | {cells} | {s['seconds']:.0f} |")
    lines += ["", "First finding of each kind, minimised (full call lists in fuzz_reproducers.json):", ""]
    lines += [f"- **{key}** ({len(r['calls'])} calls, seed {r['seed']}): {r['finding']}"
              for key, r in reproducers.items()] or ["- none"]
    (args.out / "fuzz.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
