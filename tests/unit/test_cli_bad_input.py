"""Bad input an adversarial user tries (issue 37, items 7 and 8): each gets
exit 2 and one line naming the file or the option, before any work, and
nothing is written."""
from __future__ import annotations

import json
import resource
import signal
import subprocess
import sys

import pytest

from hdjoint.io.recording import read_recording, write_recording

from cli_helpers import assert_one_line_error, files_in, rec_csv, run_cli, simulated  # noqa: F401 (fixtures)

CLI = [sys.executable, "-m", "hdjoint.app.cli"]


# ---------------------------------------------------------------- simulate


@pytest.mark.parametrize("argv, fragment", [
    (["--experiment", "bogus"], "--experiment bogus"),
    (["--duration", "inf"], "--duration inf"),
    (["--duration", "nan"], "--duration nan"),
    (["--duration", "-1"], "--duration -1"),
    (["--duration", "0"], "--duration 0"),        # was: the whole 58 s
    (["--duration", "1e-9"], "--duration 1e-09"),  # was: a one-row file the readers refuse
    (["--duration", "1e9"], "--duration 1e+09"),
    (["--duration", "5000"], "--duration 5000"),  # past the experiment's end: it ran away
])
def test_simulate_refuses_a_bad_experiment_or_duration(tmp_path, capsys, argv, fragment):
    out = tmp_path / "rec.csv"
    code, _, err = run_cli(capsys, "simulate", *argv, "-o", out)
    assert code == 2
    assert_one_line_error(err, fragment)
    assert files_in(tmp_path) == []


def test_simulate_refuses_a_negative_seed(tmp_path, capsys):
    code, _, err = run_cli(capsys, "simulate", "--duration", "0.1", "--seed", "-1", "-o", tmp_path / "r.csv")
    assert code == 2 and "--seed" in err and "Traceback" not in err
    assert files_in(tmp_path) == []


def test_simulate_the_shortest_duration_gives_a_readable_recording(tmp_path, capsys):
    out = tmp_path / "rec.csv"
    code, _, _ = run_cli(capsys, "simulate", "--duration", "0.01", "-o", out)
    assert code == 0 and len(read_recording(out)) == 11


# ---------------------------------------------------------------- parameter files


BAD_FILES = [
    ("nested", ('{"Kf": ' + "[" * 100_000 + "]" * 100_000 + "}").encode(), ["nested"]),
    ("not-utf8", b'{"Kf": 9000, "note": "\xff\xfe"}', ["UTF-8"]),
    ("5000-digits", ('{"Kf": ' + "9" * 5000 + "}").encode(), ["number"]),
    ("1000-digits", ('{"Kf": ' + "9" * 1000 + "}").encode(), ["'Kf'", "too large"]),
    ("duplicate-key", b'{"Kf": 9000, "Kf": 12000}', ["'Kf' is given twice"]),
]


@pytest.mark.parametrize("data, fragments", [b[1:] for b in BAD_FILES], ids=[b[0] for b in BAD_FILES])
def test_a_bad_parameter_file_is_refused_in_one_line(rec_csv, tmp_path, capsys, data, fragments):
    params = tmp_path / "params.json"
    params.write_bytes(data)
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "-o", tmp_path / "est.csv")
    assert code == 2
    assert_one_line_error(err, str(params), *fragments)
    assert not (tmp_path / "est.csv").exists()


def test_a_byte_order_mark_is_accepted_in_a_parameter_file_as_in_a_recording(rec_csv, tmp_path, capsys):
    params = tmp_path / "params.json"
    params.write_bytes(b"\xef\xbb\xbf" + json.dumps({"Ts": 0.001}).encode())
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "-o", tmp_path / "est.csv")
    assert code == 0, err


@pytest.mark.parametrize("tolerance", [1e308, 1e-300, 0, -0.1, "NaN"])
def test_an_unusable_tolerance_is_refused_before_any_work(rec_csv, tmp_path, capsys, tolerance):
    params = tmp_path / "params.json"
    params.write_text('{"tolerance": {"Kt": %s}}' % tolerance)
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--params", params, "--out", tmp_path / "out")
    assert code == 2
    assert_one_line_error(err, str(params), "tolerance of 'Kt'")
    assert "[diagnose]" not in err and not (tmp_path / "out").exists()


# ---------------------------------------------------------------- the time unit


def test_a_declared_unit_that_makes_the_time_base_implausible_is_refused(rec_csv, tmp_path, capsys):
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--time-unit", "ms", "-o", out)
    assert code == 2  # was: exit 0, tau_hat RMS 1.4e5 N.m and tens of thousands of warnings
    assert_one_line_error(err, str(rec_csv), "--time-unit ms", "seconds")
    assert not out.exists()


def test_diagnose_refuses_the_same_unit_slip(rec_csv, tmp_path, capsys):
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--time-unit", "us", "--out", tmp_path / "out")
    assert code == 2
    assert_one_line_error(err, str(rec_csv), "--time-unit us")


def test_a_declared_unit_that_fits_is_trusted(rec_csv, tmp_path, capsys):
    rec = read_recording(rec_csv)
    rec.time = rec.time * 1e3
    write_recording(rec_csv, rec)
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--time-unit", "ms", "-o", tmp_path / "est.csv")
    assert code == 0, err


# ---------------------------------------------------------------- a full disk


def _small_file_limit():
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # a write past the limit fails with EFBIG, like a full disk
    resource.setrlimit(resource.RLIMIT_FSIZE, (64 * 1024, 64 * 1024))


def test_a_disk_that_fills_up_during_diagnose_names_the_file_and_leaves_no_folder(rec_csv, tmp_path):
    out = tmp_path / "out"
    run = subprocess.run([*CLI, "diagnose", str(rec_csv), "--out", str(out)], capture_output=True, text=True,
                         preexec_fn=_small_file_limit)
    assert run.returncode == 2, run.stderr
    lines = [line for line in run.stderr.splitlines() if not line.startswith("[diagnose]")]
    assert len(lines) == 1 and "cannot write" in lines[0] and str(out / "report.html") in lines[0], run.stderr
    assert files_in(tmp_path) == ["rec.csv"]  # no empty --out, no staging folder, no lock


def test_a_disk_that_fills_up_during_estimate_names_the_output(rec_csv, tmp_path):
    out = tmp_path / "est.csv"
    run = subprocess.run([*CLI, "estimate", str(rec_csv), "--engine", "batch", "-o", str(out)], capture_output=True,
                         text=True, preexec_fn=_small_file_limit)
    assert run.returncode == 2
    assert_one_line_error(run.stderr, f"cannot write {out}", "nothing was written")
    assert files_in(tmp_path) == ["rec.csv"]


# ---------------------------------------------------------------- a current logged against the encoders


def test_current_sign_negates_the_current_as_it_is_read(rec_csv, tmp_path, capsys):
    rec = read_recording(rec_csv)
    rec.i_m = -rec.i_m
    flipped = tmp_path / "flipped.csv"
    write_recording(flipped, rec)
    code, _, err = run_cli(capsys, "estimate", flipped, "--engine", "batch", "--current-sign", "-1", "-o",
                           tmp_path / "a.csv")
    assert code == 0, err
    assert run_cli(capsys, "estimate", rec_csv, "--engine", "batch", "-o", tmp_path / "b.csv")[0] == 0
    assert (tmp_path / "a.csv").read_bytes() == (tmp_path / "b.csv").read_bytes()
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--current-sign", "2", "-o", tmp_path / "c.csv")
    assert code == 2 and "--current-sign" in err


def test_help_texts_are_whole_and_show_defaults(capsys):
    code, out, _ = run_cli(capsys, "--help")
    assert code == 0 and "130/143" in out and "(docs/robustness.md)." in out
    code, out, _ = run_cli(capsys, "fleet", "generate", "--help")
    assert code == 0 and "number of joints (default: 4)" in out and "(default: 6)" in out


def test_the_demos_output_folder_is_ignored_by_git():
    from pathlib import Path
    root = Path(__file__).resolve().parents[2]
    if not (root / ".git").exists():
        pytest.skip("not a git checkout")
    run = subprocess.run(["git", "-C", str(root), "check-ignore", "-q", "hdjoint-demo/report.html"])
    assert run.returncode == 0


def test_an_unexplained_residual_without_a_peak_reads_as_a_sentence():
    from hdjoint.app.cli import diagnosis_lines
    doc = {"verdict": "unexplained", "findings": [], "unexplained": [
        {"channel": "transmission", "feature": "theta_l", "largest_at": "-"},
        {"channel": "motor", "feature": "omega_m", "largest_at": "omega_m = 3.1 rad/s"}]}
    assert diagnosis_lines(doc)[1:] == ["  unexplained: transmission residual depends on theta_l",
                                        "  unexplained: motor residual depends on omega_m "
                                        "(largest at omega_m = 3.1 rad/s)"]


def test_estimate_warns_of_a_wild_sample_naming_its_line(rec_csv, tmp_path, capsys):
    rec = read_recording(rec_csv)
    rec.i_m[700] = 1e300  # the UKF skipped thousands of updates after it, silently
    write_recording(rec_csv, rec)
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--engine", "batch", "-o", tmp_path / "e.csv")
    assert code == 0
    warning = next(line for line in err.splitlines() if "wild sample" in line)
    assert str(rec_csv) in warning and "line 702 i_m = 1e+300" in warning


def test_estimate_on_a_clean_recording_warns_of_nothing(rec_csv, tmp_path, capsys):
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--engine", "batch", "-o", tmp_path / "e.csv")
    assert code == 0 and "wild" not in err
