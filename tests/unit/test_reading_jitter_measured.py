"""The encoders' reading-time jitter measured from a recording
(hdjoint.io.reading_jitter), and `hdjoint estimate` running the joint-state
filter with it (jsf_r_time) unless the parameter file sets it."""
from __future__ import annotations

import contextlib
import io
import math
from dataclasses import replace

import numpy as np
import pytest

from cli_helpers import rec_csv, run_cli, simulated  # noqa: F401 (fixtures)
from hdjoint.app import cli
from hdjoint.io import parameters
from hdjoint.io.reading_jitter import reading_jitter
from hdjoint.io.recording import write_recording
from hdjoint_truth.cases import CONTROL_CASES, draw, record

TS = 1e-3
COVERAGE = 0.95
MOTOR, LINK = 2 * math.pi / 4096, 2 * math.pi / 2 ** 19  # an encoder's count, rad


def readings(late: np.ndarray, stamp_actual: bool = False):
    """(stamps, motor, link) of a joint moving on a multisine, read LATE s after each nominal instant."""
    n = len(late)
    t = np.arange(n) * TS + late
    link = 0.5 * np.sin(2 * np.pi * 0.7 * t) + 0.2 * np.sin(2 * np.pi * 2.3 * t + 1.0)
    motor = 100 * link + 1e-3 * np.sin(2 * np.pi * 31 * t)  # a little torsion
    stamps = t if stamp_actual else np.arange(n) * TS
    return stamps, MOTOR * np.floor(motor / MOTOR), LINK * np.floor(link / LINK)


def test_a_known_jitter_is_recovered_within_its_interval():
    late = np.random.default_rng(1).uniform(0.0, 150e-6, 20_000)
    stamps, motor, link = readings(late)
    motor[[5000, 12000]] += 1.0  # wild samples are left out
    found = reading_jitter(stamps, (motor, link), COVERAGE)
    assert found.lo <= np.std(late) <= found.hi, (found, np.std(late))
    assert 0.9 * np.std(late) < found.std < 1.1 * np.std(late) and found.hi < 1.2 * found.lo
    assert found.reason == "measured from the recording"


@pytest.mark.parametrize("late, stamp_actual", [(0.0, False), (150e-6, True)], ids=["none", "actual-time stamps"])
def test_no_jitter_is_measured_where_the_stamps_are_right(late, stamp_actual):
    stamps, motor, link = readings(np.random.default_rng(2).uniform(0.0, late, 20_000), stamp_actual)
    found = reading_jitter(stamps, (motor, link), COVERAGE)
    assert found.std == 0.0 and found.hi < 5e-6, found


def test_a_still_or_short_recording_gives_none_with_the_reason():
    for n in (2, 5, 300):
        stamps, motor, link = readings(np.random.default_rng(3).uniform(0.0, 150e-6, n))
        found = reading_jitter(stamps, (motor, link), COVERAGE)
        assert found.std == 0.0 and "fewer than" in found.reason
    still = reading_jitter(np.arange(5000) * TS, (np.zeros(5000), np.full(5000, LINK)), COVERAGE)
    assert still.std == 0.0 and "fewer than" in still.reason


def _estimate(tmp_path, rec_csv, params: dict, name: str, engine: str = "fmu"):
    parameters.save(tmp_path / f"{name}.json", params)
    out, printed = tmp_path / f"{name}-{engine}.csv", io.StringIO()
    with contextlib.redirect_stdout(printed):
        assert cli.main(["estimate", str(rec_csv), "--params", str(tmp_path / f"{name}.json"), "-o", str(out),
                         "--engine", engine]) == 0
    return np.genfromtxt(out, delimiter=",", names=True)["tau_hat"], printed.getvalue()


def test_estimate_measures_the_jitter_unless_the_parameter_file_sets_it(tmp_path):
    joint = draw(next(c for c in CONTROL_CASES if c.name == "control on multisine"), 0, duration=3.0)
    run = record(joint, 1)
    assert not joint.setups[1].stamp_actual_times and joint.setups[1].jitter > 5e-5  # late, stamped on time
    write_recording(tmp_path / "run.csv", replace(run, extra={}, tau_sensor=None))
    truth = run.extra["tau_joint"]
    unstated = {k: v for k, v in joint.nominal.items() if k != "jsf_r_time"}
    rms = {}
    for name, params in (("measured", unstated), ("zero", dict(unstated, jsf_r_time=0.0))):
        tau_hat, printed = _estimate(tmp_path, tmp_path / "run.csv", params, name)
        rms[name] = float(np.sqrt(np.mean((tau_hat - truth)[300:] ** 2)))
        rms[name + " printed"] = printed
    assert rms["measured"] < 0.6 * rms["zero"], rms
    assert "measured from the recording" in rms["measured printed"], rms
    assert "0 us, as the parameter file sets it (jsf_r_time)" in rms["zero printed"], rms
    batch, printed = _estimate(tmp_path, tmp_path / "run.csv", unstated, "measured", engine="batch")
    assert printed.splitlines()[0] == rms["measured printed"].splitlines()[0]  # both engines: the same value
    assert float(np.sqrt(np.mean((batch - truth)[300:] ** 2))) == pytest.approx(rms["measured"], rel=1e-3)


def test_a_set_hdjoint_writes_leaves_the_jitter_to_each_recording_unless_the_user_set_it(tmp_path):
    # --calibrate-from and diagnose write full sets; a default 0 written out would freeze the run's own jitter.
    from hdjoint.jobs.estimate import as_written
    full = parameters.defaults()
    (tmp_path / "unstated.json").write_text('{"Kt": 0.05}')
    (tmp_path / "stated.json").write_text('{"jsf_r_time": 3e-5}')
    assert "jsf_r_time" not in as_written(full, tmp_path / "unstated.json")
    assert "jsf_r_time" not in as_written(full, None)
    assert as_written(dict(full, jsf_r_time=3e-5), tmp_path / "stated.json")["jsf_r_time"] == 3e-5


def test_motion_a_slow_logger_samples_coarsely_is_not_taken_for_jitter():
    # The paper's sinusoid logged at 250 Hz with exact stamps: the midpoint of two neighbours missed the
    # motion's curvature by as much as a 10 us jitter would move the readings; the cubic through four does not.
    from hdjoint.fmu import experiments
    rec = experiments.run("paper", duration=20.0)
    found = reading_jitter(rec.time[::4], (rec.theta_m[::4], rec.theta_l[::4]), COVERAGE)
    assert found.std == 0.0, found


def test_diagnose_writes_its_corrected_set_without_the_jitter_unless_the_user_set_it(rec_csv, tmp_path, capsys):
    # The corrected set is the joint's; the logger's jitter is each recording's own, measured where it is estimated.
    import json
    assert run_cli(capsys, "diagnose", rec_csv, "--out", tmp_path / "unstated")[0] == 0
    for name in ("params.json", "params.ssv"):
        assert "jsf_r_time" not in (tmp_path / "unstated" / name).read_text(), name
    (tmp_path / "stated.json").write_text('{"jsf_r_time": 3e-5}')
    assert run_cli(capsys, "diagnose", rec_csv, "--params", tmp_path / "stated.json", "--out", tmp_path / "stated")[0] == 0
    assert json.loads((tmp_path / "stated" / "params.json").read_text())["jsf_r_time"] == 3e-5
