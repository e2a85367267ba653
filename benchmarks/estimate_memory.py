"""Peak memory of `hdjoint estimate` on a long recording (issue 12: a 200 MB
file, 2.4 M rows, peaked at 2.0 GB). Generates the recording (a synthetic
moving joint at 1 kHz, the contract's five columns at full precision), runs
the installed command in a child process per engine and reads the child's
peak resident set size; --before PATH also runs another checkout's python/
package (e.g. the commit before streaming) against the same installed
binaries, for the comparison. Each path is an engine, alone or with
--smooth (fmu, batch, fmu+smooth, batch+smooth). Writes
docs/results/estimate_memory.md.

Run: python benchmarks/estimate_memory.py [--rows 2400000] [--paths fmu batch batch+smooth]
         [--before /tmp/old/python --before-paths batch+smooth]
"""
from __future__ import annotations

import argparse
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import stamp
import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def write_long_recording(path: Path, rows: int) -> None:
    """A joint moving through a slow sine with a torque ripple, written in blocks."""
    from hdjoint.io.recording import CsvWriter
    rng = np.random.default_rng(1)
    names = ("time", "i_m", "theta_m", "theta_l", "tau_sensor")
    with CsvWriter(path, names) as out:
        for start in range(0, rows, 200_000):
            k = np.arange(start, min(start + 200_000, rows))
            t = k * 1e-3
            theta_l = 0.5 * np.sin(2 * np.pi * 0.2 * t)
            tau = 5.0 * np.sin(2 * np.pi * 0.2 * t + 0.3) + 0.05 * rng.standard_normal(len(k))
            theta_m = 100.0 * (theta_l + tau / 3.0e4)
            i_m = tau / (100.0 * 0.1) + 0.01 * rng.standard_normal(len(k))
            out.write(dict(zip(names, (t, i_m, theta_m, theta_l, tau))))


def peak_rss(argv, env) -> tuple[float, float, int]:
    """(peak RSS in MB, seconds, exit code) of a child process."""
    start = time.monotonic()
    proc = subprocess.Popen(argv, env=env, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    _, status, usage = os.wait4(proc.pid, 0)
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        print(proc.stderr.read().decode(), file=sys.stderr)
    return usage.ru_maxrss / 1024, time.monotonic() - start, proc.returncode


def old_package(python_dir: Path, work: Path) -> Path:
    """The other checkout's pure-Python package with the installed binaries (_core, FMUs, systems) copied in."""
    import hdjoint
    installed = Path(hdjoint.__file__).parent
    target = work / "old" / "hdjoint"
    shutil.copytree(python_dir / "hdjoint", target)
    for item in installed.iterdir():
        if item.name.startswith("_core") or item.name in ("fmus", "systems"):
            (shutil.copytree if item.is_dir() else shutil.copy2)(item, target / item.name)
    return target.parent


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rows", type=int, default=2_400_000)
    ap.add_argument("--before", type=Path, help="python/ folder of another checkout to compare with")
    choices = ["fmu", "batch", "fmu+smooth", "batch+smooth"]
    ap.add_argument("--paths", nargs="+", default=choices, choices=choices, help="engine[+smooth] to run")
    ap.add_argument("--before-paths", nargs="+", choices=choices, help="those of --before (default: --paths)")
    ap.add_argument("--out", type=Path, default=ROOT / "docs" / "results")
    args = ap.parse_args(argv)
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        work = Path(tmp)
        rec = work / "long.csv"
        write_long_recording(rec, args.rows)
        size = rec.stat().st_size / 1e6
        print(f"recording: {args.rows} rows, {size:.0f} MB", file=sys.stderr)
        versions = [("this commit", None, args.paths)]
        if args.before:
            versions.insert(0, (f"before ({args.before})", old_package(args.before, work),
                                args.before_paths or args.paths))
        for label, path, paths in versions:
            env = dict(os.environ)
            if path is not None:
                env["PYTHONPATH"] = str(path)
            for run in paths:
                engine, smooth = run.split("+")[0], run.endswith("+smooth")
                out = work / f"est-{engine}.csv"
                mb, seconds, code = peak_rss([sys.executable, "-m", "hdjoint.app.cli", "estimate", str(rec),
                                              "--engine", engine, *(["--smooth"] if smooth else []),
                                              "-o", str(out)], env)
                rows.append((label, run, mb, mb / size, seconds, code))
                print(rows[-1], file=sys.stderr, flush=True)
                out.unlink(missing_ok=True)
    lines = ["# Peak memory of `hdjoint estimate` (benchmarks/estimate_memory.py)", "",
             stamp.generated_by("python benchmarks/estimate_memory.py") + " A synthetic recording of "
             f"{args.rows} rows at 1 kHz, {size:.0f} MB.", "",
             "| code | path | peak RSS (MB) | × file size | seconds | exit |", "|---|---|---:|---:|---:|---:|"]
    lines += [f"| {label} | {engine} | {mb:.0f} | {ratio:.2f} | {s:.0f} | {code} |"
              for label, engine, mb, ratio, s, code in rows]
    args.out.mkdir(parents=True, exist_ok=True)
    (args.out / "estimate_memory.md").write_text("\n".join(lines) + "\n")
    print("\n".join(lines))
    return 0


if __name__ == "__main__":
    sys.exit(main())
