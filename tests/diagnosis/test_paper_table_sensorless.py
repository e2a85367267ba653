"""The paper's table (hdjoint demo, docs/paper.md) completed: beside the
paper's rows, the compliance model, the paper's UKF, tau_hat and tau_smooth,
it shows tau_hat after a calibration without a torque sensor, all on the same
recording. The set is calibrated on another run of the same joint whose
sensor column is dropped, as `hdjoint estimate --calibrate-from` calibrates."""
import numpy as np
import pytest
from hdjoint.estimation.paper_table import reproduce
from hdjoint.fmu import experiments
from hdjoint.io import parameters
from hdjoint.io.recording import read_recording
from hdjoint.jobs.paper_joint_calibration import sensorless_set

ROW = "hdjoint: tau_hat after a sensorless calibration"


@pytest.mark.slow
def test_the_paper_table_shows_tau_hat_after_a_sensorless_calibration(tmp_path):
    rec = experiments.run("paper", duration=30.0)
    calibrated = sensorless_set(rec, tmp_path, duration=20.0)
    bench = read_recording(tmp_path / "bench_recording.csv")
    assert bench.tau_sensor is None and not np.array_equal(bench.theta_l[:100], rec.theta_l[:100])
    assert parameters.load(tmp_path / "sensorless_params.json") == pytest.approx(calibrated)
    table = reproduce(rec, calibrated=calibrated)
    rows = {name: figures for name, figures, _ in table.rows()}
    assert ROW in rows and f"| {ROW} |" in table.markdown()
    # The calibration moved the set, and tau_hat with it is no worse than with the nominal set.
    assert any(calibrated[k] != v for k, v in parameters.defaults().items() if k != "a0")
    assert rows[ROW].rms <= 1.1 * table.tau_hat.rms
    assert ROW not in {name for name, _, _ in reproduce(rec).rows()}
