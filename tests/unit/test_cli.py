"""The `hdjoint` command line: fmus, simulate, estimate, and its error contract
(exit code 2, one line on stderr naming the file, line and column, nothing written)."""
from __future__ import annotations

import contextlib
import hashlib
import io
import json
import re
import shutil
import subprocess

import numpy as np
import pytest

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.app.cli import main
from hdjoint.fmu.runner import ESTIMATOR_OUTPUTS, run_estimator_fmu
from hdjoint.fmu.shipped import FMU_NAMES, fmu_path
from hdjoint.io.recording import read_recording

from cli_helpers import assert_one_line_error, files_in, read_csv, rec_csv, rewrite, run_cli, simulated  # noqa: F401 (fixtures)

# The estimate file: time, then the estimator FMU's outputs in their table's order (hdjoint.fmu.runner).
ESTIMATE_COLUMNS = ["time", *ESTIMATOR_OUTPUTS]


# ---------------------------------------------------------------- fmus


def test_fmus_writes_every_fmu(tmp_path, capsys):
    """Both FMI versions by default: NAME.fmu (FMI 2.0) and NAME_fmi3.fmu (FMI 3.0)."""
    out = tmp_path / "new" / "dir"
    code, stdout, err = run_cli(capsys, "fmus", "--out", out)
    assert code == 0, err
    assert files_in(out) == sorted([f"{n}.fmu" for n in FMU_NAMES] + [f"{n}_fmi3.fmu" for n in FMU_NAMES])
    for name in FMU_NAMES:
        for fmi, written in ((2, out / f"{name}.fmu"), (3, out / f"{name}_fmi3.fmu")):
            shipped = fmu_path(name, fmi).read_bytes()
            assert hashlib.sha256(written.read_bytes()).digest() == hashlib.sha256(shipped).digest()
            assert str(written) in stdout


@pytest.mark.parametrize("fmi, suffix", [("2", ".fmu"), ("3", "_fmi3.fmu")])
def test_fmus_writes_one_fmi_version(tmp_path, capsys, fmi, suffix):
    code, _, err = run_cli(capsys, "fmus", "--out", tmp_path, "--fmi", fmi)
    assert code == 0, err
    assert files_in(tmp_path) == sorted(f"{n}{suffix}" for n in FMU_NAMES)


def test_fmus_into_a_file_fails_cleanly(tmp_path, capsys):
    blocker = tmp_path / "file"
    blocker.write_text("not a directory")
    code, _, err = run_cli(capsys, "fmus", "--out", blocker)
    assert code != 0
    assert_one_line_error(err, "hdjoint fmus:", str(blocker))
    assert blocker.read_text() == "not a directory"


# ---------------------------------------------------------------- simulate


def test_simulate_writes_a_contract_recording(simulated):
    header, data = read_csv(simulated)
    assert header[:5] == ["time", "i_m", "theta_m", "theta_l", "tau_sensor"]
    assert data.shape[0] == 2001
    time = data[:, 0]
    np.testing.assert_allclose(np.diff(time), 1e-3, rtol=0, atol=1e-12)
    assert time[0] == 0.0
    rec = read_recording(simulated)
    assert rec.tau_sensor is not None and np.ptp(rec.tau_sensor) > 0.2
    assert np.isfinite(data).all()
    # The encoder angles are quantised: 4096 counts per motor revolution.
    counts = rec.theta_m / (2 * np.pi / 4096)
    np.testing.assert_allclose(counts, np.round(counts), atol=1e-6)


def test_simulate_prints_a_summary_and_honours_the_seed(tmp_path, capsys):
    a, b = tmp_path / "a.csv", tmp_path / "b.csv"
    code, out, err = run_cli(capsys, "simulate", "--duration", "0.3", "--seed", "7", "-o", a)
    assert code == 0, err
    assert f"{a}: 301 samples" in out
    assert run_cli(capsys, "simulate", "--duration", "0.3", "--seed", "8", "-o", b)[0] == 0
    ra, rb = read_recording(a), read_recording(b)
    assert not np.array_equal(ra.i_m, rb.i_m)  # the current noise follows the seed
    assert not np.array_equal(ra.tau_sensor, rb.tau_sensor)


# ---------------------------------------------------------------- estimate


@pytest.fixture(scope="module")
def estimated(simulated, tmp_path_factory):
    d = tmp_path_factory.mktemp("est")
    results = {}
    for engine in ("fmu", "batch"):
        out = d / f"{engine}.csv"
        stdout = io.StringIO()
        with contextlib.redirect_stdout(stdout):
            code = main(["estimate", str(simulated), "--engine", engine, "-o", str(out)])
        assert code == 0
        results[engine] = (out, stdout.getvalue())
    return results


def test_estimate_writes_every_estimator_output(estimated, simulated, estimator_params):
    path, _ = estimated["fmu"]
    header, data = read_csv(path)
    assert header[0] == "time" and len(set(header)) == len(header)
    assert set(ESTIMATE_COLUMNS) <= set(header)
    assert set(header) <= set(ESTIMATE_COLUMNS) | {"nis"}  # the outputs the table declares
    rec = read_recording(simulated)
    assert data.shape[0] == len(rec)
    np.testing.assert_array_equal(data[:, 0], rec.time)
    expected = run_estimator_fmu(rec.time, rec.i_m, rec.theta_m, rec.theta_l, estimator_params)
    for k, name in enumerate(header[1:], start=1):
        if name in expected:
            np.testing.assert_allclose(data[:, k], expected[name], rtol=1e-15, atol=0, err_msg=name)


def test_estimate_prints_rms_and_max_against_tau_sensor(estimated, simulated):
    path, stdout = estimated["fmu"]
    header, data = read_csv(path)
    sensor = read_recording(simulated).tau_sensor
    for name in ("tau_compliance", "tau_ukf"):
        m = re.search(rf"^{name}\s+([-\d.]+)\s+([-\d.]+)\s*$", stdout, re.MULTILINE)
        assert m, f"no RMS/max line for {name} in:\n{stdout}"
        error = data[:, header.index(name)] - sensor
        assert float(m[1]) == pytest.approx(np.sqrt(np.mean(error ** 2)), abs=6e-5)
        assert float(m[2]) == pytest.approx(np.max(np.abs(error)), abs=6e-5)
        assert float(m[1]) > 0
    assert "RMS" in stdout


def test_batch_engine_gives_the_same_numbers(estimated):
    h_fmu, fmu = read_csv(estimated["fmu"][0])
    h_batch, batch = read_csv(estimated["batch"][0])
    assert set(h_fmu) == set(h_batch)
    for name in h_fmu:
        np.testing.assert_allclose(batch[:, h_batch.index(name)], fmu[:, h_fmu.index(name)], rtol=0, atol=1e-12,
                                   err_msg=name)
    assert estimated["fmu"][1] == estimated["batch"][1]  # the same RMS/max lines


def test_batch_engine_writes_the_same_file_layout(estimated):
    """Switching the engine must not change the output file: same columns in the same order."""
    h_fmu, _ = read_csv(estimated["fmu"][0])
    h_batch, _ = read_csv(estimated["batch"][0])
    assert h_batch == h_fmu


def test_estimate_smooth_adds_tau_smooth_with_either_engine(simulated, tmp_path, capsys, estimator_params):
    columns = {}
    for engine in ("fmu", "batch"):
        out = tmp_path / f"{engine}.csv"
        code, stdout, err = run_cli(capsys, "estimate", simulated, "--engine", engine, "--smooth", "-o", out)
        assert code == 0, err
        header, data = read_csv(out)
        assert header == ESTIMATE_COLUMNS + ["tau_smooth", "tau_smooth_std"]
        assert re.search(r"^tau_smooth\s+[\d.]+\s+[\d.]+\s*$", stdout, re.MULTILINE), stdout
        columns[engine] = data
    # The smoother is the batch path's in both cases: the same numbers.
    np.testing.assert_array_equal(columns["fmu"][:, -2:], columns["batch"][:, -2:])
    rec = read_recording(simulated)
    expected = _core.run_estimator(estimator_params, rec.time, rec.i_m, rec.theta_m, rec.theta_l, smooth=True)
    np.testing.assert_array_equal(columns["batch"][:, -2], expected["tau_smooth"])
    np.testing.assert_array_equal(columns["batch"][:, -1], expected["tau_smooth_std"])
    # Smoothing uses the future: it differs from the causal tau_hat. (Whether it is
    # closer to the truth depends on the model: this joint is not the nominal one.)
    hat = columns["batch"][:, ESTIMATE_COLUMNS.index("tau_hat")]
    assert not np.array_equal(hat, columns["batch"][:, -2])


def test_estimate_without_tau_sensor_prints_no_error_figures(rec_csv, tmp_path, capsys):
    rewrite(rec_csv, lambda h, rows: ([c for c in h if c != "tau_sensor"],
                                      [[c for c, n in zip(r, h) if n != "tau_sensor"] for r in rows]))
    out = tmp_path / "est.csv"
    code, stdout, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 0, err
    assert out.is_file()
    assert "RMS" not in stdout and "tau_ukf " not in stdout
    jitter, wrote = stdout.strip().splitlines()
    assert wrote == f"wrote {out} (the recording has no tau_sensor: no error figures)"  # not silence
    assert jitter.startswith("encoder reading-time jitter: 0 us") and "none" in jitter  # hdjoint's own: not late


def test_estimate_uses_the_params_file(rec_csv, tmp_path, capsys, estimated, default_params):
    params = tmp_path / "p.json"
    params.write_text(json.dumps({"Kf": 9000.0, "ukf_q_tau": 0.05}))
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "-o", out)
    assert code == 0, err
    header, data = read_csv(out)
    rec = read_recording(rec_csv)
    p = parameters.for_estimator({**default_params, "Kf": 9000.0, "ukf_q_tau": 0.05})
    expected = run_estimator_fmu(rec.time, rec.i_m, rec.theta_m, rec.theta_l, p)
    np.testing.assert_allclose(data[:, header.index("tau_ukf")], expected["tau_ukf"], rtol=1e-15, atol=0)
    _, default_run = read_csv(estimated["fmu"][0])
    assert not np.allclose(data[:, header.index("tau_ukf")], default_run[:, header.index("tau_ukf")])


def test_estimate_accepts_a_full_parameter_set(rec_csv, tmp_path, capsys, estimated, default_params):
    """A parameter set holds plant parameters too; the estimator takes its own and ignores the rest."""
    params = tmp_path / "all.json"
    parameters.save(params, default_params)
    assert "Jl" in json.loads(params.read_text())
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "-o", out)
    assert code == 0, err
    header, data = read_csv(out)
    h0, d0 = read_csv(estimated["fmu"][0])
    assert header == h0
    np.testing.assert_array_equal(data, d0)


def test_estimate_takes_ts_from_a_2ms_recording(rec_csv, tmp_path, capsys, default_params):
    rewrite(rec_csv, lambda h, rows: (h, rows[::2]))
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 0, err
    assert "Ts = 0.002" in err
    header, data = read_csv(out)
    rec = read_recording(rec_csv)
    p = parameters.for_estimator({**default_params, "Ts": 2e-3})
    expected = run_estimator_fmu(rec.time, rec.i_m, rec.theta_m, rec.theta_l, p)
    np.testing.assert_allclose(data[:, header.index("tau_ukf")], expected["tau_ukf"], rtol=1e-15, atol=0)


# ---------------------------------------------------------------- malformed recordings


def _set_cell(column, data_row, value):
    def edit(h, rows):
        rows[data_row][h.index(column)] = value
        return h, rows
    return edit


def _drop_column(column):
    def edit(h, rows):
        k = h.index(column)
        return h[:k] + h[k + 1:], [r[:k] + r[k + 1:] for r in rows]
    return edit


def _short_row(data_row):
    def edit(h, rows):
        rows[data_row] = rows[data_row][:-1]
        return h, rows
    return edit


MALFORMED = [
    # (id, edit, fragments the one-line message must hold)
    ("bad-number", _set_cell("theta_l", 16, "abc"), ["line 18", "column theta_l", "not a number"]),
    ("nan-current", _set_cell("i_m", 3, "nan"), ["line 5", "column i_m"]),
    ("empty-cell", _set_cell("theta_m", 100, ""), ["line 102", "column theta_m"]),
    ("bad-sensor", _set_cell("tau_sensor", 40, "1.2.3"), ["line 42", "column tau_sensor"]),
    ("missing-column", _drop_column("theta_l"), ["line 1", "theta_l", "missing"]),
    ("time-backwards", _set_cell("time", 28, "0.0265"), ["line 30", "column time"]),
    ("time-repeated", _set_cell("time", 28, "0.027"), ["line 30", "column time"]),
    ("short-row", _short_row(8), ["line 10"]),
]


@pytest.mark.parametrize("edit, fragments", [m[1:] for m in MALFORMED], ids=[m[0] for m in MALFORMED])
@pytest.mark.parametrize("engine", ["fmu", "batch"])
def test_malformed_recording_is_refused(rec_csv, tmp_path, capsys, edit, fragments, engine):
    rewrite(rec_csv, edit)
    out = tmp_path / "est.csv"
    before = files_in(tmp_path)
    code, stdout, err = run_cli(capsys, "estimate", rec_csv, "--engine", engine, "-o", out)
    assert code == 2
    assert_one_line_error(err, "hdjoint estimate:", str(rec_csv), *fragments)
    assert not out.exists()
    assert files_in(tmp_path) == before  # no temporary file left either


def test_malformed_recording_leaves_an_existing_output_untouched(rec_csv, tmp_path, capsys):
    rewrite(rec_csv, _set_cell("theta_m", 5, "x"))
    out = tmp_path / "est.csv"
    out.write_text("precious\n")
    code, _, err = run_cli(capsys, "estimate", rec_csv, "-o", out)
    assert code == 2 and "line 7" in err
    assert out.read_text() == "precious\n"


def test_missing_recording_file(tmp_path, capsys):
    missing = tmp_path / "nope.csv"
    code, _, err = run_cli(capsys, "estimate", missing, "-o", tmp_path / "est.csv")
    assert code == 2
    assert_one_line_error(err, str(missing))
    assert not (tmp_path / "est.csv").exists()


# ---------------------------------------------------------------- bad parameter files


BAD_PARAMS = [
    ("unknown-name", '{"Kf": 9000, "K_typo": 1}', ["K_typo", "unknown"]),
    ("out-of-range", '{"N": 0}', ["'N'", "range"]),
    ("negative-range", '{"Kf": -5}', ["'Kf'", "range"]),
    ("invalid-json", '{"Kf": 9000,\n "N": }', ["line 2", "JSON"]),
    ("not-a-number", '{"Kf": "stiff"}', ["'Kf'"]),
    ("not-an-object", '[1, 2]', ["object"]),
    ("nan", '{"Kf": NaN}', ["'Kf'"]),
]


@pytest.mark.parametrize("text, fragments", [b[1:] for b in BAD_PARAMS], ids=[b[0] for b in BAD_PARAMS])
def test_bad_params_file_is_refused_naming_it(rec_csv, tmp_path, capsys, text, fragments):
    params = tmp_path / "params.json"
    params.write_text(text)
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "-o", out)
    assert code == 2
    assert_one_line_error(err, str(params), *fragments)
    assert not out.exists()


def test_bad_params_file_for_simulate(tmp_path, capsys):
    params = tmp_path / "params.json"
    params.write_text('{"Jl": 0}')
    out = tmp_path / "rec.csv"
    code, _, err = run_cli(capsys, "simulate", "--duration", "0.1", "--params", params, "-o", out)
    assert code == 2
    assert_one_line_error(err, str(params), "Jl")
    assert not out.exists()


def test_missing_params_file(rec_csv, tmp_path, capsys):
    params = tmp_path / "nothere.json"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "-o", tmp_path / "est.csv")
    assert code == 2
    assert_one_line_error(err, str(params))


# ---------------------------------------------------------------- singular torsion


@pytest.mark.parametrize("engine", ["fmu", "batch"])
def test_singular_torsion_from_the_params(rec_csv, tmp_path, capsys, engine):
    params = tmp_path / "params.json"
    params.write_text('{"a0": 0.5}')  # a 0.5 rad offset: far beyond the atan law's asymptote
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--params", params, "--engine", engine, "-o", out)
    assert code == 2
    assert_one_line_error(err, str(rec_csv), "singular torsion")
    assert not out.exists()


@pytest.mark.parametrize("engine", ["fmu", "batch"])
def test_a_link_encoder_glitch_is_treated_as_missing(rec_csv, tmp_path, capsys, engine):
    def edit(h, rows):
        k = h.index("theta_l")
        rows[700][k] = repr(float(rows[700][k]) + 0.05)  # a glitch on line 702: faster than the joint can move
        return h, rows
    rewrite(rec_csv, edit)
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--engine", engine, "-o", out)
    assert code == 0, err
    assert "no sensor could produce" in err, err
    assert ("sample 700" if engine == "fmu" else "0.7 s") in err, err  # where: the sample (FMU) / the time (batch)
    assert out.exists()


@pytest.mark.parametrize("engine", ["fmu", "batch"])
def test_singular_torsion_in_the_recording(rec_csv, tmp_path, capsys, engine):
    def edit(h, rows):
        k = h.index("theta_l")
        for row in rows[700:]:  # the link encoder slips by 5 mrad at line 702, within the joint's speed
            row[k] = repr(float(row[k]) + 0.005)
        return h, rows
    rewrite(rec_csv, edit)
    out = tmp_path / "est.csv"
    code, _, err = run_cli(capsys, "estimate", rec_csv, "--engine", engine, "-o", out)
    assert code == 2
    # The glitch's first 0.1 s is predicted over (the FMU engine's warnings); then the error, one line.
    assert_one_line_error(err.strip().splitlines()[-1], "hdjoint estimate:", str(rec_csv), "singular torsion")
    assert "since sample 700" in err  # where it began
    assert not out.exists()


# ---------------------------------------------------------------- the installed console script


def test_console_script_exit_codes(simulated, tmp_path):
    exe = shutil.which("hdjoint")
    assert exe, "the hdjoint console script is not installed"
    bad = tmp_path / "bad.csv"
    shutil.copyfile(simulated, bad)
    rewrite(bad, _set_cell("i_m", 9, "oops"))
    out = tmp_path / "est.csv"
    run = subprocess.run([exe, "estimate", str(bad), "-o", str(out)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert_one_line_error(run.stderr, str(bad), "line 11", "column i_m", "not a number")
    assert "oops" not in run.stderr  # a file's content never appears in a message (issue 56)
    assert not out.exists()
    assert "Traceback" not in run.stderr
