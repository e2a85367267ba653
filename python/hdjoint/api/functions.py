"""The API's functions: what the `hdjoint` subcommands do, on Python objects.

Each runs the same job as its subcommand (`hdjoint.jobs`), so the numbers
are the command line's; files are staged in a temporary folder and read
back. A recording is a `Recording` or a CSV path; a parameter set a
`Parameters`, a dict of name: value, a JSON path or None (the defaults).
Bad input raises `UserError` (the message the command line prints)."""
from __future__ import annotations

import math
import os
import tempfile
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Any, Union

from hdjoint.api.parameters import Parameters
from hdjoint.api.results import Calibration, Diagnosis
from hdjoint.io.recording import Recording
from hdjoint.jobs.inputs import UserError

__all__ = ["read_recording", "simulate", "estimate", "diagnose", "calibrate", "export_fmus", "UserError",
           "check_experiment", "SHORTEST_SIMULATION"]

PathLike = Union[str, os.PathLike]
RecordingLike = Union[Recording, PathLike]
ParametersLike = Union[Parameters, Mapping[str, float], PathLike, None]
# The shortest recording simulate writes: ten samples at 1 kHz (the readers need two rows, a fit more).
SHORTEST_SIMULATION = 0.01


def read_recording(path: PathLike, time_unit: str | None = None, current_sign: float = 1.0) -> Recording:
    """A recording CSV (contract columns, SI units), its time base checked;
    TIME_UNIT the time column's unit ("s", "ms", "us", "ns"; None: seconds,
    refused when implausible); CURRENT_SIGN -1 for a current logged against
    the encoders' sense.

    >>> import hdjoint, tempfile, os
    >>> path = os.path.join(tempfile.mkdtemp(), "paper.csv")
    >>> hdjoint.simulate("paper", duration=0.5).save(path)
    >>> hdjoint.read_recording(path)
    Recording(.../paper.csv: 501 samples, 0.5 s at 1 kHz; time, i_m, theta_m, theta_l, tau_sensor, ...)
    """
    from hdjoint.jobs.inputs import read_recording as read
    return read(path, time_unit, current_sign)


def check_experiment(experiment: str, duration: float | None) -> None:
    """Refuse an unknown built-in experiment, or a duration outside SHORTEST_SIMULATION..its length (UserError)."""
    from hdjoint.fmu import experiments
    if experiment not in experiments.EXPERIMENTS:
        raise UserError(f"--experiment {experiment}: unknown; known: {', '.join(experiments.EXPERIMENTS)}")
    if duration is not None:
        longest = experiments.EXPERIMENTS[experiment].duration
        if not math.isfinite(duration) or not SHORTEST_SIMULATION <= duration <= longest:
            raise UserError(f"--duration {duration:g}: must be from {SHORTEST_SIMULATION:g} s to the experiment's "
                            f"length, {longest:g} s ({experiment}); leave it out for the whole experiment")


def simulate(experiment: str = "paper", *, params: ParametersLike = None, joint: ParametersLike = None,
             duration: float | None = None, seed: int = 1) -> Recording:
    """Run the joint FMU under the built-in controller on EXPERIMENT ("paper",
    "paper_repeated", "multisine", "sweep", "chirp"): a recording with a
    torque sensor. PARAMS is the nominal set the controller assumes; JOINT
    the simulated joint (default: PARAMS with realistic deviations); SEED
    the sensor noise's.

    >>> import hdjoint
    >>> rec = hdjoint.simulate("paper", duration=0.5)
    >>> len(rec), rec.duration
    (501, 0.5)
    """
    from hdjoint.fmu import experiments
    check_experiment(experiment, duration)
    nominal = Parameters.coerce(params).to_dict()
    truth = Parameters.coerce(joint).to_dict() if joint is not None else experiments.true_joint_parameters(nominal)
    return experiments.run(experiment, joint=truth, nominal=nominal, duration=duration,
                           sensors=experiments.Sensors(seed=seed))


class _Staged:
    """A temporary folder holding the files a job reads: a Recording or a Parameters is written there; a path is
    passed on as it is (so a parameter file's own statements, e.g. its Ts, hold as on the command line)."""

    def __init__(self):
        self._tmp = tempfile.TemporaryDirectory(prefix="hdjoint-api-")
        self.folder = Path(self._tmp.name)
        self._count = 0

    def __enter__(self) -> "_Staged":
        return self

    def __exit__(self, *exc) -> None:
        self._tmp.cleanup()

    def _name(self, stem: str, suffix: str) -> Path:
        self._count += 1
        return self.folder / f"{stem}-{self._count}{suffix}"

    def recording(self, rec: RecordingLike) -> str:
        if isinstance(rec, Recording):
            path = self._name(Path(rec.path).stem if rec.path else "recording", ".csv")
            rec.save(path)
            return str(path)
        return os.fspath(rec)

    def params(self, params: ParametersLike) -> str | None:
        if params is None or isinstance(params, (str, os.PathLike)):
            return None if params is None else os.fspath(params)
        path = self._name("params", ".json")
        Parameters.coerce(params).save(path)
        return str(path)

    def output(self, name: str) -> str:
        return str(self.folder / name)


def _recordings(recordings: RecordingLike | Sequence[RecordingLike]) -> list[RecordingLike]:
    if isinstance(recordings, (Recording, str, os.PathLike)):
        return [recordings]
    return list(recordings)


def _name(rec: RecordingLike) -> str:
    if isinstance(rec, Recording):
        return rec.path or "in memory"
    return os.fspath(rec)


def _table(path: str) -> Any:
    """The estimates CSV (numbers parsed exactly, as written) as a pandas DataFrame indexed by time, else a
    numpy structured array."""
    import numpy as np
    with open(path) as f:
        header = f.readline().strip().split(",")
    data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    try:
        import pandas as pd
    except ImportError:
        return np.rec.fromarrays(data.T, names=header).view(np.ndarray)
    return pd.DataFrame(data[:, 1:], index=pd.Index(data[:, 0], name="time"), columns=header[1:])


def estimate(recording: RecordingLike, params: ParametersLike = None, *, engine: str = "fmu",
             smooth: bool = False, calibrate_from: RecordingLike | Sequence[RecordingLike] | None = None,
             time_unit: str | None = None, split_gaps: bool = False, allow_jitter: bool = False,
             current_sign: float = 1.0) -> Any:
    """Torque estimates on RECORDING, row by row as `hdjoint estimate`
    writes them: tau_ukf, tau_compliance, tau_hat, their deviations, ...
    (docs/estimators.md); with SMOOTH also tau_smooth. With CALIBRATE_FROM
    (recordings without a torque sensor will do) PARAMS is first calibrated
    on them. ENGINE "fmu" runs JointTorqueEstimator.fmu, "batch" the native path.

    Returns a pandas DataFrame indexed by time when pandas is installed
    (`.attrs["error_figures"]`: RMS and max error against tau_sensor, N.m;
    `.attrs["reading_jitter"]`), else a numpy structured array with a "time" field.

    >>> import hdjoint
    >>> est = hdjoint.estimate(hdjoint.simulate("paper", duration=0.5), engine="batch")
    >>> len(est), "tau_hat" in est.dtype.names if hasattr(est, "dtype") else "tau_hat" in est.columns
    (501, True)
    """
    from hdjoint.jobs.estimate import Options, estimate_to_file
    with _Staged() as staged:
        opts = Options(recording=staged.recording(recording), output=staged.output("estimates.csv"),
                       params=staged.params(params), engine=engine, smooth=smooth, time_unit=time_unit,
                       split_gaps=split_gaps, allow_jitter=allow_jitter, current_sign=current_sign)
        if calibrate_from is not None:
            from hdjoint.jobs.sensorless_calibration import estimate_calibrated
            estimated, _ = estimate_calibrated(opts, [staged.recording(r) for r in _recordings(calibrate_from)])
        else:
            estimated = estimate_to_file(opts)
        table = _table(opts.output)
    if hasattr(table, "attrs"):
        table.attrs["error_figures"] = {name: {"rms": f.rms, "max": f.max} for name, f in estimated.figures.items()}
        table.attrs["reading_jitter"] = estimated.jitter.describe()
    return table


def diagnose(recordings: RecordingLike | Sequence[RecordingLike], params: ParametersLike = None, *,
             validate: Sequence[RecordingLike] = (), time_unit: str | None = None,
             current_sign: float = 1.0, out: PathLike | None = None) -> Diagnosis:
    """What the model PARAMS leaves out of RECORDINGS (one, or several of one
    joint fitted jointly), as `hdjoint diagnose`: the verdict, findings, the
    corrected set and the report; VALIDATE are other recordings of the joint
    the corrected model is checked on; OUT, a folder to keep the files in
    (findings.json, params.json, params.ssv, report.html). Takes seconds to a minute.

    >>> import hdjoint
    >>> d = hdjoint.diagnose(hdjoint.simulate("paper", duration=4.0))
    >>> d.verdict in ("consistent", "missing_physics", "unexplained"), type(d.corrected).__name__
    (True, 'Parameters')
    """
    from hdjoint.jobs.diagnose import diagnose_to_directory
    with _Staged() as staged:
        paths = [staged.recording(r) for r in _recordings(recordings)]
        folder = staged.output("diagnosis") if out is None else out
        document = diagnose_to_directory(paths, staged.params(params), folder,
                                         [staged.recording(r) for r in validate], time_unit, current_sign)
        found = Diagnosis.load(folder)  # the corrected set and the report as written
    return Diagnosis(document, found.corrected, found._report, [_name(r) for r in _recordings(recordings)])


def calibrate(recordings: RecordingLike | Sequence[RecordingLike], params: ParametersLike = None, *,
              time_unit: str | None = None, current_sign: float = 1.0) -> Calibration:
    """PARAMS calibrated on RECORDINGS of the joint, no torque sensor needed
    (the first half of `hdjoint estimate --calibrate-from`): every parameter
    at its estimate, the torque scale from the tolerances. Its `.params` go
    to `estimate` (whose `calibrate_from` also places the encoder zero a0).

    >>> import hdjoint
    >>> cal = hdjoint.calibrate(hdjoint.simulate("paper", duration=4.0))
    >>> type(cal.params).__name__, cal.scale > 0
    ('Parameters', True)
    """
    from hdjoint.jobs.sensorless_calibration import calibrate_from
    from hdjoint.jobs.estimate import as_written
    with _Staged() as staged:
        params_path = staged.params(params)
        calibrated = calibrate_from([staged.recording(r) for r in _recordings(recordings)], params_path,
                                    time_unit, current_sign)
        given = Parameters.coerce(params)
        used = Parameters(as_written(calibrated.params, params_path), tolerance=given.tolerance,
                          accuracy=given.accuracy, sensor_noise=given.sensor_noise)
    return Calibration(used, calibrated.verdict, calibrated.scale, calibrated.scale_interval,
                       calibrated.describe_scale(), calibrated.calibration)


def export_fmus(out: PathLike, fmi: Sequence[int] = (2, 3)) -> list[Path]:
    """Write the FMUs (JointTorqueEstimator, HarmonicDriveJoint,
    JointController) into OUT: FMI 2.0 as NAME.fmu, FMI 3.0 as NAME_fmi3.fmu.

    >>> import hdjoint, tempfile
    >>> sorted(p.name for p in hdjoint.export_fmus(tempfile.mkdtemp(), fmi=(2,)))
    ['HarmonicDriveJoint.fmu', 'JointController.fmu', 'JointTorqueEstimator.fmu']
    """
    from hdjoint.fmu.shipped import export_fmus as export
    return export(out, tuple(fmi))
