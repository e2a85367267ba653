"""A fleet estimate row carries the encoders' reading-time jitter the filter
ran with (est.jsf_r_time, with its interval), as `hdjoint estimate` measured
it: a logger that starts reading late shows in the fleet's table."""
from dataclasses import replace

from hdjoint.fleet.inputs import Job
from hdjoint.fleet.tasks import estimate
from hdjoint.io import parameters
from hdjoint.io.recording import write_recording
from hdjoint_truth.cases import CONTROL_CASES, draw, record


def test_a_late_logger_shows_in_the_estimate_row(tmp_path):
    joint = draw(next(c for c in CONTROL_CASES if c.name == "control on multisine"), 0, duration=3.0)
    setup = joint.setups[1]
    assert not setup.stamp_actual_times and setup.jitter > 5e-5  # read late, stamped on time
    write_recording(tmp_path / "run.csv", replace(record(joint, 1), extra={}))
    parameters.save(tmp_path / "nominal.json", {k: v for k, v in joint.nominal.items() if k != "jsf_r_time"})
    job = Job(recording=str(tmp_path / "run.csv"), params=str(tmp_path / "nominal.json"), joint="j1",
              date="2026-01-01", name="run")
    row = estimate(job, tmp_path / "out", "batch")
    # Drawn uniform in [0, jitter] (std jitter/sqrt(12)), then read at the truth's next integration substep:
    # the delays' std is up to about twice that.
    late = setup.jitter / 12 ** 0.5
    assert row["est.jsf_r_time.lo"] <= row["est.jsf_r_time"] <= row["est.jsf_r_time.hi"]
    assert 0.5 * late < row["est.jsf_r_time"] < 3.0 * late, (row, late)
    assert "est.tau_hat.rms" in row  # beside the error figures against the sensor
