"""The paper experiment's joint calibrated without a torque sensor, for the
demo's table: another built-in experiment on the same simulated joint (its
own excitation and noise), its sensor column dropped, calibrated as
`hdjoint estimate --calibrate-from` calibrates, and the set placed on the
paper recording. It lives here, above the estimation layer that builds the
table, because the calibration is the diagnosis's."""
from __future__ import annotations

from dataclasses import replace
from pathlib import Path

from hdjoint.fmu import experiments
from hdjoint.io import parameters
from hdjoint.io.recording import Recording, write_recording
from hdjoint.jobs.sensorless_calibration import calibrate_from, placed_on

# The bench recording: an excitation the paper's sinusoid is not, with other sensor noise.
BENCH_EXPERIMENT = "multisine"
BENCH_NOISE_SEED = 7


def sensorless_set(run: Recording, folder: Path, duration: float | None = None) -> dict:
    """The parameter set `hdjoint estimate --calibrate-from` would estimate RUN
    with: the default nominal set calibrated on a bench recording of the same
    joint without its torque sensor, written to FOLDER as bench_recording.csv
    (the recording) and sensorless_params.json (the set, a0 placed on RUN)."""
    folder.mkdir(parents=True, exist_ok=True)
    bench = experiments.run(BENCH_EXPERIMENT, duration=duration, sensors=experiments.Sensors(seed=BENCH_NOISE_SEED))
    write_recording(folder / "bench_recording.csv", replace(bench, tau_sensor=None))
    parameters.save(folder / "nominal_params.json", parameters.defaults())
    calibrated = calibrate_from([str(folder / "bench_recording.csv")], str(folder / "nominal_params.json"))
    placed = placed_on(run, calibrated.params)
    parameters.save(folder / "sensorless_params.json", placed)
    return placed
