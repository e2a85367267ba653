"""Screening before the diagnosis (issue 37, items 4 and 5): one wild sample
in any channel is found and left out, and findings.json and the report say
how many and where; a degenerate recording (zeros, encoders that never move,
a wrapping encoder) is refused naming the reason; findings.json is strict
JSON. The real command on real files."""
from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from hdjoint.fmu import experiments
from hdjoint.io.recording import read_recording, write_recording
from hdjoint.io.screening import find_outliers

CLI = [sys.executable, "-m", "hdjoint.app.cli"]
ROW = 1500  # the wild sample's data row (line ROW + 2)


@pytest.fixture(scope="module")
def clean(tmp_path_factory):
    """A 3 s recording and its diagnosis."""
    d = tmp_path_factory.mktemp("clean")
    path = d / "rec.csv"
    write_recording(path, experiments.run("paper", duration=3.0))
    run = subprocess.run([*CLI, "diagnose", str(path), "--out", str(d / "out")], check=False, capture_output=True, text=True)
    assert run.returncode == 0, run.stderr
    return path, json.loads((d / "out" / "findings.json").read_text())


def _diagnose(path, out):
    run = subprocess.run([*CLI, "diagnose", str(path), "--out", str(out)], check=False, capture_output=True, text=True)
    return run.returncode, run.stdout, run.stderr


@pytest.mark.parametrize("channel, value", [
    ("tau_sensor", 1e3),       # the issue's: missing_physics became consistent
    ("tau_sensor", 10.0),      # the issue's: backlash and wave-generator compliance appeared
    ("i_m", 1e300),            # the UKF skipped thousands of updates
    ("theta_l", 0.5),
    ("theta_m", 10.0),
])
def test_one_wild_sample_is_left_out_and_named(clean, tmp_path, channel, value):
    path, expected = clean
    rec = read_recording(path)
    getattr(rec, channel)[ROW] = value if value > 1e100 else getattr(rec, channel)[ROW] + value
    spiked = tmp_path / "spiked.csv"
    write_recording(spiked, rec)
    code, out, err = _diagnose(spiked, tmp_path / "out")
    assert code == 0, err
    doc = json.loads((tmp_path / "out" / "findings.json").read_text())
    (entry,) = doc["screening"]
    assert entry["outliers_left_out"] == 1 and entry["by_channel"] == {channel: 1}
    assert entry["outliers"][0]["line"] == ROW + 2 and entry["outliers"][0]["channel"] == channel
    assert f"line {ROW + 2}" in out and f"line {ROW + 2}" in (tmp_path / "out" / "report.html").read_text()
    # The diagnosis is the clean recording's.
    assert doc["verdict"] == expected["verdict"]
    assert [f["effect"] for f in doc["findings"]] == [f["effect"] for f in expected["findings"]]
    for part, sigma in expected["noise"].items():
        assert doc["noise"][part] == pytest.approx(sigma, rel=0.05), part


def test_a_clean_recording_has_no_outliers(clean):
    _, doc = clean
    assert doc["screening"][0]["outliers_left_out"] == 0


@pytest.mark.parametrize("experiment", ["paper", "multisine", "sweep", "chirp"])
def test_no_sample_of_a_clean_simulated_recording_is_an_outlier(experiment):
    rec = experiments.run(experiment, duration=20.0)
    for name in ("i_m", "theta_m", "theta_l", "tau_sensor"):
        assert len(find_outliers(getattr(rec, name), rec.time)) == 0, name


def test_no_sample_of_the_lara8_recordings_is_an_outlier():
    from pathlib import Path
    for path in sorted((Path(__file__).resolve().parents[1] / "data" / "lara8").glob("*.csv")):
        rec = read_recording(path)
        for name in ("i_m", "theta_m", "theta_l"):
            assert len(find_outliers(getattr(rec, name), rec.time)) == 0, (path.name, name)


def _edited(clean, tmp_path, edit):
    rec = read_recording(clean[0])
    edit(rec)
    path = tmp_path / "rec.csv"
    write_recording(path, rec)
    return path


@pytest.mark.parametrize("edit, fragments", [
    (lambda r: [getattr(r, c).__setitem__(slice(None), 0.0) for c in ("i_m", "theta_m", "theta_l", "tau_sensor")],
     ["column i_m", "never varies"]),
    (lambda r: [getattr(r, c).__setitem__(slice(None), 0.25) for c in ("theta_m", "theta_l")],
     ["column theta_m", "never moves"]),
    (lambda r: setattr(r, "theta_l", np.angle(np.exp(1j * 40 * r.theta_l))),
     ["column theta_l", "wraps", "line "]),
])
def test_a_degenerate_recording_is_refused_naming_why(clean, tmp_path, edit, fragments):
    path = _edited(clean, tmp_path, edit)
    code, _, err = _diagnose(path, tmp_path / "out")
    assert code == 2, err
    line = err.strip().splitlines()[-1]
    assert line.startswith(f"hdjoint diagnose: {path}") and all(f in line for f in fragments), line
    assert "NaN" not in err and "Singular" not in err and not (tmp_path / "out").exists()


def test_estimate_names_a_wrapping_encoder(clean, tmp_path):
    path = _edited(clean, tmp_path, lambda r: setattr(r, "theta_l", np.angle(np.exp(1j * 40 * r.theta_l))))
    run = subprocess.run([*CLI, "estimate", str(path), "-o", str(tmp_path / "e.csv")], check=False, capture_output=True, text=True)
    assert run.returncode == 2 and "wraps" in run.stderr and "column theta_l" in run.stderr


def test_a_fast_motor_logged_slowly_is_no_wrap():
    from hdjoint.io.recording import Recording
    from hdjoint.io.screening import check_no_wrap
    t = np.arange(200) * 0.01
    check_no_wrap(Recording(time=t, i_m=np.ones(200), theta_m=400.0 * t, theta_l=4.0 * t))  # 4 rad a sample


def test_findings_json_is_strict_json(clean):
    path, _ = clean
    text = (path.parent / "out" / "findings.json").read_text()

    def refuse(constant):
        raise ValueError(f"not strict JSON: {constant}")
    json.loads(text, parse_constant=refuse)


def test_strict_json_turns_every_non_finite_number_into_null():
    from hdjoint.io.screening import strict_json
    doc = {"a": math.nan, "b": [np.float64(np.inf), 1.5, np.int64(3)], "c": {"d": -math.inf},
           "e": np.array([1.0, np.nan])}
    assert json.dumps(strict_json(doc), allow_nan=False) == \
        '{"a": null, "b": [null, 1.5, 3], "c": {"d": null}, "e": [1.0, null]}'


# ---------------------------------------------------------------- the report reads as numbers, once


def test_the_report_never_shows_minus_zero(clean):
    import re
    path, _ = clean
    page = re.sub(r"data:image/png;base64,[A-Za-z0-9+/=]+", "", (path.parent / "out" / "report.html").read_text())
    assert not re.search(r"-0\.0+(?![0-9])", page)


def test_what_to_record_next_names_each_reason_once():
    from hdjoint.diagnosis.output.report import _summary
    reason = "not testable on this recording: the motor reverses fewer than twice"
    doc = {"verdict": "consistent", "findings": [], "beyond_tolerance": [], "calibration": {}, "unexplained": [],
           "cannot_tell": [], "not_testable": [{"effect": e, "reason": reason}
                                               for e in ("wave_generator_load", "coulomb_friction", "hysteresis")]}
    text = _summary(doc)
    assert text.count("the motor reverses fewer than twice") == 1
    assert "wave_generator_load, coulomb_friction, hysteresis" in text


def test_the_calibration_table_gives_each_parameter_its_unit_and_meaning(clean):
    path, _ = clean
    page = (path.parent / "out" / "report.html").read_text()
    assert "<td>Kt</td><td>N.m/A</td><td>motor torque constant</td>" in page
    assert "<td>Kf</td><td>N.m/rad</td><td>flexspline stiffness at zero torque</td>" in page


@pytest.mark.parametrize("figure", ["residual_vs_feature", "order_spectrum"])
def test_the_nominal_curve_shows_beneath_an_equal_corrected_one(figure):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from hdjoint.diagnosis.output import plots
    x = np.linspace(0.0, 10.0, 500)
    y = np.sin(3 * x)
    fig, ax = plt.subplots()
    if figure == "residual_vs_feature":
        plots.residual_vs_feature(ax, x, y, y.copy(), "speed")
    else:
        plots.order_spectrum(ax, x, y, y.copy(), [1, 2, 3], "theta_m")
    nominal, corrected = (line for line in ax.get_lines() if line.get_label() in ("calibrated nominal", "corrected"))
    assert nominal.get_label() == "calibrated nominal"
    assert corrected.get_linestyle() == "--" and nominal.get_linewidth() > corrected.get_linewidth()
    plt.close(fig)


def test_a_residual_the_findings_leave_unchanged_is_drawn_visibly_and_said_so():
    """The motor channel's residual over time, unchanged by a transmission finding: the corrected
    trace was drawn over the nominal one and hid it (legend: two curves; image: one blue trace)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from hdjoint.diagnosis.output import plots
    t = np.linspace(0.0, 10.0, 2000)
    y = np.random.default_rng(0).standard_normal(t.size)
    fig, ax = plt.subplots()
    plots.residual_over_time(ax, t, y, y.copy(), [], "motor residual")
    fig.canvas.draw()
    image = np.asarray(fig.canvas.buffer_rgba())[..., :3].astype(int)
    red = (image[..., 0] > 150) & (image[..., 2] < 120)
    assert red.mean() > 0.01, "the nominal (red) trace is hidden"
    assert [line.get_label() for line in ax.get_lines()] == [
        "calibrated nominal model = corrected model (unchanged here)"]
    plt.close(fig)
    fig, ax = plt.subplots()
    plots.residual_over_time(ax, t, y, 0.5 * y, [], "transmission residual")
    assert [line.get_label() for line in ax.get_lines()] == ["calibrated nominal model", "corrected model"]
    plt.close(fig)


def test_a_controllers_own_sharp_current_samples_are_kept_not_refused():
    """The independent truth's position controller answers each motor
    encoder count with a one-sample current spike near a reversal: hundreds
    in a 30 s run, far more than a few wild samples. They are the channel's
    own: screening keeps it as recorded and says so (it refused the recording
    as too noisy, and the independent benchmark stopped at its first case)."""
    from diagnosis_independent import CONTROL_CASES, draw, record
    from hdjoint.io.screening import MAX_OUTLIER_SHARE, screen
    rec = record(draw(CONTROL_CASES[0], 0, 30.0), 0)
    assert len(find_outliers(rec.i_m, rec.time)) > MAX_OUTLIER_SHARE * len(rec.i_m)
    kept, found = screen(rec)
    assert np.array_equal(kept.i_m, rec.i_m) and not found.outliers
    assert found.kept_as_recorded["i_m"] > 30
    assert "i_m kept as recorded" in found.summary() and found.as_dict()["kept_as_recorded"] == found.kept_as_recorded
