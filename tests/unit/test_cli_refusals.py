"""What the command line refuses because it would silently go wrong
(issue 12): writing over its input, a time column in the wrong unit or at
another rate than Ts, gaps and jitter, output locations that cannot work.
Exit code 2, one line naming the user's file, nothing written."""
from __future__ import annotations

import os

import numpy as np
import pytest

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.io.recording import iter_recording, read_recording, write_recording

from cli_helpers import assert_one_line_error, files_in, read_csv, rec_csv, run_cli, simulated  # noqa: F401 (fixtures)


def scaled_time(rec_csv, factor):
    rec = read_recording(rec_csv)
    rec.time = rec.time * factor
    write_recording(rec_csv, rec)
    return rec_csv


# ---------------------------------------------------------------- never over the input


@pytest.mark.parametrize("via", ["same path", "dot-dot path", "symlink", "hard link"])
def test_estimate_never_writes_over_its_recording(rec_csv, tmp_path, capsys, via):
    before = rec_csv.read_bytes()
    out = {"same path": rec_csv, "dot-dot path": tmp_path / "sub" / ".." / rec_csv.name,
           "symlink": tmp_path / "link.csv", "hard link": tmp_path / "hard.csv"}[via]
    (tmp_path / "sub").mkdir()
    if via == "symlink":
        out.symlink_to(rec_csv)
    elif via == "hard link":
        os.link(rec_csv, out)
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 2
    assert_one_line_error(err, str(out), "refusing to write over it")
    assert rec_csv.read_bytes() == before
    assert not [p for p in files_in(tmp_path) if p.endswith(".tmp")]


def test_estimate_never_writes_over_its_params(rec_csv, tmp_path, capsys):
    params = tmp_path / "p.json"
    params.write_text('{"Ts": 0.001}\n')
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "-o", params)
    assert code == 2 and params.read_text() == '{"Ts": 0.001}\n'
    assert_one_line_error(err, str(params), "refusing")


def test_diagnose_never_writes_over_its_recording(rec_csv, tmp_path, capsys):
    target = tmp_path / "out"
    target.mkdir()
    inside = target / "report.html"
    os.link(rec_csv, inside)
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--out", target)
    assert code == 2
    assert_one_line_error(err, str(inside), "refusing")
    assert files_in(target) == ["report.html"]


# ---------------------------------------------------------------- the time base


@pytest.mark.parametrize("unit, factor, name", [("ms", 1e3, "milliseconds"), ("us", 1e6, "microseconds")])
def test_time_in_another_unit_is_refused_naming_it(rec_csv, tmp_path, capsys, unit, factor, name):
    scaled_time(rec_csv, factor)
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 2
    assert_one_line_error(err, str(rec_csv), name, f"--time-unit {unit}")
    assert "fmi2SetReal" not in err and not out.exists()


@pytest.mark.parametrize("unit, factor", [("ms", 1e3), ("us", 1e6)])
def test_time_unit_option_converts_to_seconds(simulated, rec_csv, tmp_path, capsys, unit, factor):
    reference = tmp_path / "ref.csv"
    assert run_cli(capsys, "estimate", simulated, "-o", reference)[0] == 0
    scaled_time(rec_csv, factor)
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--time-unit", unit, "-o", out)
    assert code == 0, err
    (h, a), (_, b) = read_csv(out), read_csv(reference)
    np.testing.assert_allclose(a[:, 0], b[:, 0], rtol=1e-12, atol=1e-15)
    np.testing.assert_allclose(a[:, 1:], b[:, 1:], rtol=1e-6, atol=1e-9)


def test_a_recording_at_another_rate_than_ts_is_refused(rec_csv, tmp_path, capsys):
    scaled_time(rec_csv, 2.0)  # 2 ms steps
    params = tmp_path / "p.json"
    params.write_text('{"Ts": 0.001}\n')
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "-o", tmp_path / "e.csv")
    assert code == 2
    assert_one_line_error(err, str(rec_csv), "0.002", "Ts = 0.001")


def test_ms_time_against_ts_names_the_unit(rec_csv, tmp_path, capsys):
    scaled_time(rec_csv, 1e3)
    params = tmp_path / "p.json"
    params.write_text('{"Ts": 0.001}\n')
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "--time-unit", "s",
                           "-o", tmp_path / "e.csv")
    assert code == 2
    assert_one_line_error(err, "milliseconds", "--time-unit ms")


def test_diagnose_refuses_ms_time_naming_the_unit_before_any_work(rec_csv, tmp_path, capsys):
    scaled_time(rec_csv, 1e3)
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--out", tmp_path / "d")
    assert code == 2
    assert_one_line_error(err, "milliseconds", "--time-unit ms")
    assert "too short" not in err and not (tmp_path / "d").exists()


# ---------------------------------------------------------------- gaps and jitter


def with_gap(rec_csv, at=1000, seconds=1.0):
    rec = read_recording(rec_csv)
    rec.time[at:] += seconds
    write_recording(rec_csv, rec)
    return rec


def test_a_gap_is_refused_naming_its_lines(rec_csv, tmp_path, capsys):
    with_gap(rec_csv)
    out = tmp_path / "e.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 2
    # data row 1000 is line 1001, the gap runs from line 1001 to 1002
    assert_one_line_error(err, str(rec_csv), "a gap of 1.001 s", "lines 1001 to 1002", "--split-gaps")
    assert not out.exists()


@pytest.mark.parametrize("engine", ["fmu", "batch"])
def test_split_gaps_restarts_the_estimator_after_each_gap_and_warns(rec_csv, tmp_path, capsys, engine):
    rec = with_gap(rec_csv)
    out = tmp_path / "e.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--split-gaps", "--engine", engine, "-o", out)
    assert code == 0, err
    assert "warning:" in err and "a gap of 1.001 s" in err and "lines 1001 to 1002" in err
    header, data = read_csv(out)
    assert len(data) == len(rec)
    # After the gap: what the estimator gives on that part alone, started afresh.
    params = parameters.for_estimator(parameters.defaults())
    part = rec.slice(1000)
    alone = _core.run_estimator(params, part.time, part.i_m, part.theta_m, part.theta_l)
    np.testing.assert_allclose(data[1000:, header.index("tau_ukf")], alone["tau_ukf"], rtol=0, atol=1e-9)
    before = rec.slice(0, 1000)
    alone = _core.run_estimator(params, before.time, before.i_m, before.theta_m, before.theta_l)
    np.testing.assert_allclose(data[:1000, header.index("tau_ukf")], alone["tau_ukf"], rtol=0, atol=1e-9)


def test_jitter_is_refused_unless_allowed(rec_csv, tmp_path, capsys):
    rec = read_recording(rec_csv)
    rng = np.random.default_rng(4)
    rec.time = rec.time + rng.uniform(-0.15, 0.15, len(rec)) * 1e-3  # steps up to 30 % off
    write_recording(rec_csv, rec)
    out = tmp_path / "e.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 2
    assert_one_line_error(err, str(rec_csv), "a jittered step", "--allow-jitter")
    assert not out.exists()
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--allow-jitter", "-o", out)
    assert code == 0, err
    assert len(read_csv(out)[1]) == len(rec)


# ---------------------------------------------------------------- output locations, before any work


def test_output_in_a_missing_directory_is_a_usage_error(rec_csv, tmp_path, capsys):
    out = tmp_path / "missing" / "e.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 2
    assert_one_line_error(err, str(out), "does not exist")
    assert ".tmp" not in err


def test_output_that_is_a_directory_is_a_usage_error(rec_csv, tmp_path, capsys):
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", tmp_path)
    assert code == 2
    assert_one_line_error(err, str(tmp_path), "is a directory")


def test_diagnose_checks_its_output_directory_before_the_analysis(rec_csv, tmp_path, capsys):
    out = tmp_path / "d"
    (out / "findings.json").mkdir(parents=True)
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--out", out)
    assert code == 2
    assert_one_line_error(err, str(out / "findings.json"), "is a directory")
    assert "[diagnose]" not in err  # no progress line: refused before any analysis
    assert files_in(out / "findings.json") == []


def test_diagnose_out_that_is_a_file_is_refused(rec_csv, tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    code, _, err = run_cli(capsys, "diagnose", rec_csv, "--out", blocker)
    assert code == 2
    assert_one_line_error(err, str(blocker), "not a directory")


def test_simulate_checks_its_output_before_running(tmp_path, capsys):
    out = tmp_path / "missing" / "r.csv"
    code, _, err = run_cli(capsys, "simulate", "--duration", "0.2", "-o", out)
    assert code == 2
    assert_one_line_error(err, str(out), "does not exist")


# ---------------------------------------------------------------- exit codes


@pytest.mark.parametrize("argv", [["estimate"], ["estimate", "x.csv"], ["nonsense"], ["estimate", "x.csv", "-o",
                                                                                      "y.csv", "--time-unit", "h"]])
def test_argparse_usage_errors_exit_2(capsys, argv):
    code, _, err = run_cli(capsys, *argv)
    assert code == 2 and "usage:" in err


def test_help_exits_0(capsys):
    code, out, _ = run_cli(capsys, "estimate", "--help")
    assert code == 0 and "--split-gaps" in out and "--time-unit" in out


# ---------------------------------------------------------------- streaming


def test_the_reader_streams_a_block_before_reading_the_rest(rec_csv):
    """A block comes out before a malformed line further down is reached:
    nothing holds the whole file."""
    with open(rec_csv, "a") as f:
        f.write("9,x,0,0,0\n")
    blocks = iter_recording(rec_csv, rows=500)
    first = next(blocks)
    assert len(first.recording) == 500 and first.lines[0] == 2
    with pytest.raises(ValueError, match="line 2003"):
        list(blocks)


def test_blocks_join_to_the_whole_recording(simulated, tmp_path, capsys, monkeypatch):
    """Tiny blocks (7 rows) give the same estimates as one block."""
    from hdjoint.io import recording
    whole = tmp_path / "whole.csv"
    assert run_cli(capsys, "estimate", simulated, "-o", whole)[0] == 0
    monkeypatch.setattr(recording, "CHUNK_ROWS", 7)
    monkeypatch.setattr(recording.iter_recording, "__defaults__", (7,))
    small = tmp_path / "small.csv"
    code, out, err = run_cli(capsys, "estimate", simulated, "-o", small)
    assert code == 0, err
    assert small.read_bytes() == whole.read_bytes()


def test_an_fmu_error_names_the_failed_call_once():
    from hdjoint.fmu.runner import FmuError, run_estimator_fmu
    with pytest.raises(FmuError) as caught:
        run_estimator_fmu(np.arange(3) * 1e-3, np.zeros(3), np.zeros(3), np.zeros(3), {"Ts": 1000.0})
    assert str(caught.value).count("fmi2SetReal") == 1, str(caught.value)
    assert "Ts = 1000" in str(caught.value)


def test_a_gap_between_two_blocks_is_found_and_split_alike(rec_csv, tmp_path, capsys, monkeypatch):
    """The gap is the step into the second block (rows 0-999, then 1000-...)."""
    from hdjoint.io import recording
    with_gap(rec_csv)
    whole = tmp_path / "whole.csv"
    assert run_cli(capsys, "estimate", rec_csv, "--split-gaps", "-o", whole)[0] == 0
    monkeypatch.setattr(recording.iter_recording, "__defaults__", (1000,))
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", tmp_path / "refused.csv")
    assert code == 2
    assert_one_line_error(err, "a gap of 1.001 s", "lines 1001 to 1002")
    blocks = tmp_path / "blocks.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--split-gaps", "-o", blocks)
    assert code == 0 and "lines 1001 to 1002" in err
    assert blocks.read_bytes() == whole.read_bytes()
