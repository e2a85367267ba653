"""Peak memory of `hdjoint` on inputs no recorder writes (issue 56: "memory
bounded on any input"): /dev/zero as a recording and as a parameter file,
one endless line, a huge header and a sparse file of NULs, each beside the
working set of a legitimate recording of the same command. Runs the
installed command in a child process per input and reads its peak resident
set size (estimate_memory.peak_rss); writes docs/results/hostile_input_memory.md.

Run: python benchmarks/hostile_input_memory.py [--seconds 60] [--size-mb 700]
"""
from __future__ import annotations

import argparse
import os
import subprocess
import sys
import tempfile
from pathlib import Path

import stamp
from estimate_memory import peak_rss

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "results" / "hostile_input_memory.md"
HDJOINT = [sys.executable, "-m", "hdjoint.app.cli"]
# The bound issue 56 asks for: a hostile input's peak within this multiple of a legitimate one's.
BOUND = 2.0


def hostile_inputs(work: Path, size_mb: int, legit: Path) -> dict[str, list[str]]:
    """{what: hdjoint arguments} for each hostile input, its files written into `work`."""
    endless = work / "endless_line.csv"
    with open(endless, "wb") as f:  # one line of digits, no newline
        block = b"1," * (1 << 19)
        for _ in range(size_mb):
            f.write(block)
    header = work / "huge_header.csv"
    with open(header, "wb") as f:  # a header of size_mb/8 MB of column names, then a valid row
        f.write(b"time,i_m,theta_m,theta_l,")
        names = b"column_with_a_long_name," * (1 << 15)
        for _ in range((size_mb << 17) // len(names)):  # in blocks: this process stays small (see main)
            f.write(names)
        f.write(b"x\n0,0,0,0\n")
    sparse = work / "sparse_nuls.csv"
    with open(sparse, "wb") as f:  # a hole of size_mb MB: reads as NULs, takes no disk
        f.truncate(size_mb << 20)
    out = str(work / "out.csv")
    return {
        "/dev/zero as the recording": ["estimate", "/dev/zero", "-o", out],
        f"one endless line ({size_mb} MB, no newline)": ["estimate", str(endless), "-o", out],
        f"a header of {size_mb // 8} MB": ["estimate", str(header), "-o", out],
        f"a sparse file of {size_mb} MB of NULs": ["estimate", str(sparse), "-o", out],
        "/dev/zero as --params": ["estimate", str(legit), "--params", "/dev/zero", "-o", out],
    }


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=60.0, help="length of the legitimate recording")
    ap.add_argument("--size-mb", type=int, default=700, help="size of the endless line and the sparse file")
    args = ap.parse_args(argv)
    env = dict(os.environ)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        legit = work / "legit.csv"
        # Written by a child: a child's peak RSS starts at its parent's when forked, so this process
        # keeps only a few MB and every figure is the command's own.
        subprocess.run([sys.executable, "-c", f"import sys; sys.path.insert(0, {str(Path(__file__).parent)!r}); "
                        f"from estimate_memory import write_long_recording as w; w({str(legit)!r}, "
                        f"{int(args.seconds * 1000)})"], check=True)
        base, secs, code = peak_rss([*HDJOINT, "estimate", str(legit), "-o", str(work / "legit_out.csv")], env)
        rows.append((f"a legitimate {args.seconds:g} s recording", base, secs, code))
        for what, cli in hostile_inputs(work, args.size_mb, legit).items():
            rss, secs, code = peak_rss([*HDJOINT, *cli], env)
            rows.append((what, rss, secs, code))
    worst = max(r[1] for r in rows[1:]) / rows[0][1]
    lines = [f"# Peak memory on hostile inputs (benchmarks/hostile_input_memory.py)", "",
             stamp.generated_by("python benchmarks/hostile_input_memory.py " + " ".join(argv or sys.argv[1:])),
             f"Engine commit: {stamp.engine()}.", "",
             f"`hdjoint estimate` on each input in a child process; peak resident set size against the legitimate "
             f"recording's. Bound asked: {BOUND:g}×. Worst hostile input: **{worst:.2f}×** "
             f"({'within' if worst <= BOUND else 'beyond'} the bound). Exit 2 is a refusal naming the input.", "",
             "| input | peak RSS (MB) | × legitimate | seconds | exit |", "|---|---:|---:|---:|---:|"]
    for what, rss, secs, code in rows:
        lines.append(f"| {what} | {rss:.0f} | {rss / rows[0][1]:.2f} | {secs:.1f} | {code} |")
    OUT.write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0 if worst <= BOUND else 1


if __name__ == "__main__":
    sys.exit(main())
