"""`hdjoint fleet diagnose|estimate|generate`: registered on the main
command line by `register`, implemented in this package."""
from __future__ import annotations

import sys


def _common(p) -> None:
    p.add_argument("recordings", nargs="+", metavar="GLOB",
                   help='recordings: files or glob patterns, quoted ("logs/**/*.csv"; ** spans folders)')
    p.add_argument("--params-map", metavar="MAP",
                   help="JSON object from glob patterns (relative to MAP's folder) to parameter files; first "
                        "match wins; the matched pattern is the joint id (default: each recording's folder, "
                        "with the default parameters)")
    p.add_argument("--joint-pattern", metavar="REGEX",
                   help="regex on the recording's path relative to MAP's folder with named groups 'joint' "
                        "and optionally 'date' (default date: the file's modification time)")
    p.add_argument("--out", required=True, metavar="DIR", help="fleet.parquet, fleet.html and DIR/<joint>/<recording>/")
    where = p.add_mutually_exclusive_group()
    where.add_argument("--scheduler", metavar="ADDR", help="a running Dask scheduler (tcp://host:8786)")
    where.add_argument("--workers", type=int, metavar="N",
                       help=f"worker processes of the local cluster, at most {WORKERS_PER_CORE} a core "
                            "(default: one per core)")
    p.add_argument("--allowed-failures", type=int, default=None, metavar="K",
                   help="worker deaths one recording may cause before it is marked failed (local cluster; "
                        "default 2)")
    p.add_argument("--quiet", action="store_true", help="no progress line")


def cmd_fleet(args) -> int:
    from hdjoint.jobs.inputs import UserError
    from hdjoint.fleet.run import ALLOWED_FAILURES, run_fleet
    if args.workers is not None and not 1 <= args.workers <= max_workers():
        raise UserError(f"--workers {args.workers}: must be from 1 to {max_workers()} ({WORKERS_PER_CORE} a core "
                        f"on this machine's {available_cores()}); each worker is a process")
    options = {"engine": args.engine} if args.fleet_command == "estimate" else {}
    summary = run_fleet(args.fleet_command, args.recordings, args.out, params_map=args.params_map,
                        joint_pattern=args.joint_pattern, scheduler=args.scheduler, workers=args.workers,
                        options=options, show_progress=not args.quiet,
                        allowed_failures=ALLOWED_FAILURES if args.allowed_failures is None else args.allowed_failures)
    from hdjoint.io.outputs import printable
    print(f"{len(summary.rows)} recordings: {summary.computed} processed now, {summary.cached} done earlier, "
          f"{summary.failed} failed; wrote {printable(summary.parquet)} and {printable(summary.html)}")
    if summary.rows and summary.failed == len(summary.rows):
        first = next(r for r in summary.rows if r.get("status") != "ok")
        print(printable(f"hdjoint fleet: every recording failed ({summary.failed}); the first, {first['recording']}: "
                        f"{first.get('error')}"), file=sys.stderr)
        return 1
    from hdjoint.fleet.trend import rank_joints
    for d in rank_joints(summary.rows)[:5]:
        if d.drifting:
            print(f"  drifting: {d.joint}: {d.effect} {d.direction} ({d.strongest.quantity} "
                  f"{100 * d.strongest.change:+.0f} % over the period, p = {d.p_value:.2g})")
    return 0


# The most worker processes a local cluster is given, per core: beyond, they only contend for the cores and memory.
WORKERS_PER_CORE = 4


def available_cores() -> int:
    import os
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else (os.cpu_count() or 1)


def max_workers() -> int:
    return WORKERS_PER_CORE * available_cores()


def cmd_generate(args) -> int:
    from hdjoint.fleet.generate import JOINT_PATTERN, generate
    from hdjoint.jobs.inputs import written_folder
    with written_folder(args.out, "OUT"):
        path = generate(args.out, joints=args.joints, days=args.days, duration=args.duration,
                        progress=lambda m: print(f"[generate] {m}", file=sys.stderr, flush=True))
    from hdjoint.io.outputs import printable
    print(f"wrote {args.joints} joints x {args.days} days under {printable(args.out)}; params map {printable(path)}")
    print(f"try: hdjoint fleet diagnose '{args.out}/logs/**/*.csv' --params-map {path} "
          f"--joint-pattern '{JOINT_PATTERN}' --out FLEET")
    return 0


def whole_number(least: int):
    """An argparse type: an integer of at least LEAST, refused with a one-line reason otherwise."""
    import argparse

    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"not an integer: {text!r}") from None
        if value < least:
            raise argparse.ArgumentTypeError(f"must be at least {least}, not {value}")
        return value
    return parse


def help_formatter():
    """argparse's formatter, with the examples' lines kept as written (the description is wrapped as usual)."""
    import argparse

    class Help(argparse.HelpFormatter):
        def _fill_text(self, text, width, indent):
            if text.startswith("examples:"):
                return "".join(indent + line for line in text.splitlines(keepends=True))
            return super()._fill_text(text, width, indent)
    return Help


def subcommand(sub, name: str, summary: str, description: str, *examples: str):
    """A subcommand with its one-line summary (in the parent's --help), its description and examples (in its
    own); the main command line's too."""
    return sub.add_parser(name, help=summary, description=f"{summary[0].upper()}{summary[1:]}. {description}",
                          epilog="examples:\n" + "\n".join(f"  {e}" for e in examples),
                          formatter_class=help_formatter())


def register(sub) -> None:
    """Add `fleet` and its subcommands to the main parser's subparsers."""
    fleet = subcommand(sub, "fleet", "diagnose or estimate a fleet of recordings on Dask; fleet drift report",
                    "Resumable: a recording done earlier is not run again (docs/fleet.md).",
                    "hdjoint fleet generate fleet-demo --joints 2 --days 3",
                    "hdjoint fleet diagnose \"logs/**/*.csv\" --params-map map.json --out fleet/")
    fsub = fleet.add_subparsers(dest="fleet_command", required=True)
    p = subcommand(fsub, "diagnose", "diagnose every recording (findings, corrected parameters, report each)",
                "Writes fleet.parquet (a row per recording), fleet.html (joints ranked by drift) and each "
                "recording's diagnosis under OUT.",
                "hdjoint fleet diagnose \"logs/**/*.csv\" --params-map map.json --out fleet/ --workers 2")
    _common(p)
    p.set_defaults(run=cmd_fleet)
    p = subcommand(fsub, "estimate", "torque estimates for every recording (and error figures vs the sensor)",
                "Writes fleet.parquet, fleet.html and each recording's estimates.csv under OUT.",
                "hdjoint fleet estimate \"logs/**/*.csv\" --out fleet-est/ --engine batch")
    _common(p)
    p.add_argument("--engine", choices=("fmu", "batch"), default="fmu",
                   help="JointTorqueEstimator.fmu through fmpy (default) or the native batch path")
    p.set_defaults(run=cmd_fleet)
    p = subcommand(fsub, "generate", "simulate a fleet with known drifts (for trying the fleet commands)",
                "Writes OUT/logs/<robot>/<joint>/<date>.csv, OUT/params/, OUT/params-map.json and OUT/truth.json "
                "(which joints drift, in what).",
                "hdjoint fleet generate fleet-demo --joints 2 --days 3 --duration 5")
    p.add_argument("out", help="target directory")
    p.add_argument("--joints", type=whole_number(1), default=4, help="number of joints (default: 4)")
    p.add_argument("--days", type=whole_number(1), default=6, help="recordings per joint, one a day (default: 6)")
    p.add_argument("--duration", type=float, default=20.0, help="seconds per recording (default: 20)")
    p.set_defaults(run=cmd_generate)
