"""The `hdjoint` command line. Exit code 0 on success; otherwise a one-line
reason on stderr and a non-zero code: 2 for usage and input errors (bad
arguments, unreadable or malformed files, a time base or output location
that would go wrong), 1 for a failure while running. docs/robustness.md.
Heavy modules are imported inside the subcommands, so `hdjoint --help` is quick."""
from __future__ import annotations

import argparse
import os
import signal
import sys

from hdjoint.app.outcome import TOLD, told
from hdjoint.io.outputs import printable
from hdjoint.jobs.inputs import UserError, check_output_file, locked_output, read_params as _params, written_folder
from hdjoint.fleet.cli import help_formatter, subcommand, whole_number
from hdjoint.io.timebase import TIME_UNITS

DESCRIPTION = ("Torque sensing for harmonic-drive robot joints: FMUs, simulation, torque estimation, diagnosis, "
               "fleets. Exit code 0 on success, 2 for bad input or an output that must not be written, 1 for a "
               "failure while running, 130/143 when stopped by SIGINT/SIGTERM (docs/robustness.md).")
# The shortest recording simulate writes (hdjoint.api.functions.SHORTEST_SIMULATION), for the help text.
SHORTEST_SIMULATION = 0.01


def cmd_fmus(args) -> int:
    from hdjoint.api import export_fmus
    from hdjoint.fmu.shipped import FMI_VERSIONS
    versions = FMI_VERSIONS if args.fmi == "both" else (int(args.fmi),)
    with written_folder(args.out):
        written = export_fmus(args.out, versions)
    for path in written:
        print(printable(path))
    return 0


def cmd_simulate(args) -> int:
    from hdjoint.api.functions import check_experiment, simulate
    check_experiment(args.experiment, args.duration)
    check_output_file(args.output, inputs=(args.params, args.joint))  # before any work
    nominal = _params(args.params)
    joint = _params(args.joint) if args.joint else None
    with locked_output(args.output):
        rec = simulate(args.experiment, params=nominal, joint=joint, duration=args.duration, seed=args.seed)
        rec.save(args.output)
    print(f"{printable(args.output)}: {len(rec)} samples, {rec.duration:.3f} s ({args.experiment})")
    return 0


def cmd_params(args) -> int:
    from hdjoint.io import parameters
    if args.output:
        check_output_file(args.output, inputs=(args.params,))
    values = _params(args.params)  # the defaults, or a file's set with the defaults for the rest
    try:
        tolerance, keep = parameters.load_tolerances(args.params), parameters.stated(args.params)
    except parameters.ParameterError as e:
        raise UserError(str(e)) from None
    if args.output is None:
        import json
        print(json.dumps(parameters.documented(values, tolerance, keep), indent=2))
        return 0
    with locked_output(args.output):
        parameters.save_documented(args.output, values, tolerance, keep)
    print(f"wrote {args.output}: {len(values)} parameters with units, ranges, descriptions and the diagnosis's "
          f"tolerances; edit it and pass it as --params")
    return 0


def cmd_estimate(args) -> int:
    from hdjoint.jobs.estimate import Options, estimate_to_file
    opts = Options(recording=args.recording, output=args.output, params=args.params, engine=args.engine,
                   smooth=args.smooth, time_unit=args.time_unit, split_gaps=args.split_gaps,
                   allow_jitter=args.allow_jitter, current_sign=args.current_sign)
    if args.calibrate_from:
        from hdjoint.jobs.sensorless_calibration import estimate_calibrated, sidecars
        estimated, calibrated = estimate_calibrated(opts, args.calibrate_from)
        print(f"calibrated set: {sidecars(args.output)[0]} (its calibration: {sidecars(args.output)[1]})")
        print(calibrated.describe_scale())
    else:
        estimated = estimate_to_file(opts)
    print(estimated.jitter.describe())
    figures = estimated.figures
    if figures:
        print(f"{'estimate':<16} {'RMS error':>10} {'max error':>10}   (N.m, against tau_sensor)")
        for name, fig in figures.items():
            print(f"{name:<16} {fig.rms:>10.4f} {fig.max:>10.4f}")
    else:
        print(f"wrote {printable(args.output)} (the recording has no tau_sensor: no error figures)")
    return 0


def cmd_diagnose(args) -> int:
    from hdjoint.api import diagnose
    doc = diagnose(args.recording, args.params, validate=args.validate, time_unit=args.time_unit,
                   current_sign=args.current_sign, out=args.out).document
    for line in diagnosis_lines(doc):
        print(line)
    print(f"wrote {printable(args.out)}/findings.json, params.json, params.ssv, report.html ({doc['seconds']} s)")
    return 0


def diagnosis_lines(doc: dict) -> list[str]:
    """What `hdjoint diagnose` prints of its findings document."""
    from hdjoint.diagnosis import summary_line
    lines = [f"verdict: {doc['verdict']}"]
    from hdjoint.io.screening import found_anything
    lines += [f"  screening: {s['recording']}: {s['summary']}" for s in doc.get("screening", []) if found_anything(s)]
    for f in doc["findings"]:
        fit = f["fit"]
        lines.append(f"  {f['effect']:<28} {f['where']['part']:<13} confidence {f['confidence']:.2f}  held-out RMS "
                     f"{fit['holdout_rms_before']:.4f} -> {fit['holdout_rms_after']:.4f} N.m")
    for u in doc["unexplained"]:
        where = f" (largest at {u['largest_at']})" if u.get("largest_at") not in (None, "", "-") else ""
        lines.append(f"  unexplained: {u['channel']} residual depends on {u['feature']}{where}")
    lines += [f"  validation: {summary_line(v)}" for v in doc.get("validation", [])]
    return lines


def cmd_demo(args) -> int:
    from pathlib import Path

    from hdjoint.app.demo import run_demo
    with written_folder(args.out):
        run_demo(Path(args.out))
    return 0


def _time_unit_argument(p) -> None:
    p.add_argument("--time-unit", choices=tuple(TIME_UNITS),
                   help="unit of the recording's time column (default: seconds, refused when implausible)")
    p.add_argument("--current-sign", type=int, choices=(1, -1), default=1,
                   help="-1: the current i_m is logged against the encoders' positive sense (e.g. LARA8 joints 1 "
                        "and 2); it is negated as it is read (default: 1)")


def _version() -> str:
    import hdjoint
    return f"hdjoint {hdjoint.__version__}"


class _Version(argparse.Action):
    """--version, with the version looked up only when asked (importlib.metadata costs time)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, default=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest=dest, default=default, nargs=0, help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(_version())
        parser.exit()


def build_parser() -> argparse.ArgumentParser:
    ap = argparse.ArgumentParser(prog="hdjoint", description=DESCRIPTION,
                                 epilog="examples:\n  hdjoint demo --out hdjoint-demo\n  hdjoint estimate --help",
                                 formatter_class=help_formatter())
    ap.add_argument("--version", action=_Version, help="print the version and exit")
    sub = ap.add_subparsers(dest="command", required=True)

    p = subcommand(sub, "fmus", "write every FMU the project builds into a directory",
                   "JointTorqueEstimator, HarmonicDriveJoint and JointController, each as FMI 2.0 (NAME.fmu) and "
                   "FMI 3.0 (NAME_fmi3.fmu) Co-Simulation; each carries its sources and documentation.",
                   "hdjoint fmus --out fmus/", "hdjoint fmus --out fmus/ --fmi 3")
    p.add_argument("--out", required=True, help="target directory")
    p.add_argument("--fmi", choices=("2", "3", "both"), default="both",
                   help="FMI version: 2 (NAME.fmu), 3 (NAME_fmi3.fmu) or both (default)")
    p.set_defaults(run=cmd_fmus)

    p = subcommand(sub, "simulate", "run the joint FMU on a built-in experiment, write a recording",
                   "The joint under the built-in position controller; the recording has the contract's columns "
                   "and tau_sensor (the transmitted torque with sensor noise).",
                   "hdjoint simulate --experiment paper -o paper.csv",
                   "hdjoint simulate --experiment multisine --duration 10 --joint joint.json -o bench.csv")
    p.add_argument("--experiment", default="paper",
                   help="built-in experiment: paper, paper_repeated, multisine, sweep or chirp (default: paper)")
    p.add_argument("--params", help="nominal parameter set (JSON) the controller assumes")
    p.add_argument("--joint", help="parameter set (JSON) of the simulated joint "
                                   "(default: the nominal set with realistic deviations)")
    p.add_argument("--duration", type=float,
                   help=f"seconds, from {SHORTEST_SIMULATION:g} to the experiment's length "
                        "(default: the whole experiment)")
    p.add_argument("--seed", type=whole_number(0), default=1, help="seed of the sensor noise (an integer >= 0; default 1)")
    p.add_argument("-o", "--output", required=True, help="recording to write (CSV)")
    p.set_defaults(run=cmd_simulate)

    p = subcommand(sub, "estimate", "torque estimates on a recording",
                   "One row per sample: tau_ukf (the paper's UKF), tau_compliance, tau_hat (joint-state filter), "
                   "their deviations, ...; RMS and max error printed when the recording has tau_sensor "
                   "(docs/estimators.md).",
                   "hdjoint estimate paper.csv --params joint.json -o est.csv",
                   "hdjoint estimate run.csv --calibrate-from bench.csv -o est.csv")
    p.add_argument("recording")
    p.add_argument("--params", help="parameter set (JSON)")
    p.add_argument("--engine", choices=("fmu", "batch"), default="fmu",
                   help="run JointTorqueEstimator.fmu through fmpy (default) or the native batch path")
    p.add_argument("--smooth", action="store_true",
                   help="add tau_smooth: the RTS smoother over the joint-state filter (offline; always computed "
                        "by the native batch path, also with --engine fmu)")
    p.add_argument("-o", "--output", required=True, help="estimates to write (CSV); never the recording itself")
    _time_unit_argument(p)
    p.add_argument("--split-gaps", action="store_true",
                   help="at a gap (a step over 10 median steps) restart the estimator instead of refusing the "
                        "recording; each gap is named in a warning")
    p.add_argument("--allow-jitter", action="store_true",
                   help="accept steps more than 20 %% off the median step (the estimator still samples every Ts)")
    p.add_argument("--calibrate-from", nargs="+", metavar="RECORDING",
                   help="first calibrate the joint of --params on these recordings (no torque sensor needed; "
                        "every parameter at its estimate, the torque scale from all tolerances), then estimate with that set; "
                        "writes OUTPUT's .params.json and .calibration.json beside it")
    p.set_defaults(run=cmd_estimate)

    p = subcommand(sub, "diagnose", "locate and name what the model leaves out of a recording",
                   "Calibrates the model, tests each effect it lacks on held-out data, and writes the findings, "
                   "the corrected set and a report (docs/diagnosis.md). A recording with a gap is refused: split "
                   "it at the gap.",
                   "hdjoint diagnose bench.csv --params joint.json --out diag/",
                   "hdjoint diagnose a.csv b.csv --out diag/ --validate c.csv")
    p.add_argument("recording", nargs="+",
                   help="one recording, or several of the same joint (their shared parameters are fitted jointly)")
    p.add_argument("--params", help="the nominal parameter set (JSON; an optional \"tolerance\" object "
                                    "states relative tolerances, e.g. {\"Kt\": 0.1})")
    p.add_argument("--out", required=True, help="directory for findings.json, params.json, params.ssv, report.html")
    p.add_argument("--validate", nargs="+", default=[], metavar="RECORDING",
                   help="other recordings of the same joint: the corrected model is checked on them (never fitted)")
    _time_unit_argument(p)
    p.set_defaults(run=cmd_diagnose)

    p = subcommand(sub, "params", "write a documented parameter file",
                   "Every parameter's value with its unit, range, description and the diagnosis's tolerance, in "
                   "the form --params reads back (docs/estimators.md); from the defaults, or a partial file "
                   "completed with them.",
                   "hdjoint params --defaults -o joint.json", "hdjoint params --params mine.json -o full.json")
    given = p.add_mutually_exclusive_group(required=True)
    given.add_argument("--defaults", action="store_true", help="the default set (the paper's joint)")
    given.add_argument("--params", help="a parameter file (JSON), completed with the defaults")
    p.add_argument("-o", "--output", help="file to write (default: print to standard output)")
    p.set_defaults(run=cmd_params)

    p = subcommand(sub, "demo", "the main job on built-in data: FMUs, the paper's table, a hidden effect named without a "
                   "torque sensor and closed on a second recording (index.html)",
                   "Takes a few minutes on 2 cores; open OUT/index.html.", "hdjoint demo --out hdjoint-demo")
    p.add_argument("--out", default="hdjoint-demo", help="output directory (default: hdjoint-demo)")
    p.set_defaults(run=cmd_demo)

    from hdjoint.fleet.cli import register as register_fleet
    register_fleet(sub)
    return ap


class Terminated(BaseException):
    """SIGTERM, raised like a KeyboardInterrupt so every temporary file is removed on the way out."""


_MAIN_PID = None  # the process that installed the handler; a forked worker dies of SIGTERM as usual


def _terminate(signum, frame):
    if os.getpid() != _MAIN_PID:
        signal.signal(signal.SIGTERM, signal.SIG_DFL)
        os.kill(os.getpid(), signal.SIGTERM)
        return
    raise Terminated()


def main(argv=None) -> int:
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as e:  # argparse: --help (0) or a usage error (2), already printed
        return e.code
    global _MAIN_PID
    previous = None
    try:
        _MAIN_PID = os.getpid()
        previous = signal.signal(signal.SIGTERM, _terminate)
    except ValueError:  # not the main thread: the host handles its signals
        pass
    try:
        return args.run(args)
    except TOLD as e:  # one line, one exit-code layer for every command (app/outcome.py)
        return told(args.command, e)
    except KeyboardInterrupt:  # one line, no traceback; the jobs' cleanups have run
        print(f"hdjoint {args.command}: interrupted (SIGINT); no output was left half-written", file=sys.stderr)
        return 128 + signal.SIGINT
    except Terminated:
        print(f"hdjoint {args.command}: terminated (SIGTERM); no output was left half-written", file=sys.stderr)
        return 128 + signal.SIGTERM
    finally:
        if previous is not None:
            signal.signal(signal.SIGTERM, previous)


if __name__ == "__main__":
    sys.exit(main())
