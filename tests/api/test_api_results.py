"""The API's results: estimates as a DataFrame indexed by time (a numpy
structured array without pandas) holding the numbers `hdjoint estimate`
writes; a Finding's repr is one line in words and units."""
import sys

import numpy as np
import pytest

import hdjoint
from cli_helpers import read_csv, run_cli


@pytest.fixture(scope="module")
def short(tmp_path_factory):
    path = tmp_path_factory.mktemp("api") / "short.csv"
    hdjoint.simulate("paper", duration=1.0).save(path)
    return path


def test_estimate_is_the_command_lines(short, tmp_path, capsys):
    pd = pytest.importorskip("pandas")
    est = hdjoint.estimate(short, engine="batch")
    assert isinstance(est, pd.DataFrame) and est.index.name == "time"
    code, _, err = run_cli(capsys, "estimate", short, "--engine", "batch", "-o", tmp_path / "est.csv")
    assert code == 0, err
    header, rows = read_csv(tmp_path / "est.csv")
    assert list(est.columns) == header[1:]
    np.testing.assert_array_equal(est.index.to_numpy(), rows[:, 0])
    np.testing.assert_array_equal(est.to_numpy(), rows[:, 1:])
    assert set(est.attrs["error_figures"]) >= {"tau_ukf", "tau_hat"}


def test_estimate_without_pandas_is_a_structured_array(short, monkeypatch):
    monkeypatch.setitem(sys.modules, "pandas", None)  # import pandas raises ImportError
    est = hdjoint.estimate(hdjoint.read_recording(short), {"Kt": 0.046}, engine="batch")
    assert isinstance(est, np.ndarray) and est.dtype.names[0] == "time" and "tau_hat" in est.dtype.names
    assert len(est) == 1001


def test_a_finding_reads_as_one_line_with_units():
    entry = {"effect": "viscous_friction", "kind": "added", "confidence": 0.998, "where": {"part": "motor"},
             "parameters": {"Bm": 1.52e-4}, "intervals": {"Bm": [1.3e-4, 1.73e-4]},
             "fit": {"holdout_rms_before": 0.13, "holdout_rms_after": 0.0123}}
    text = repr(hdjoint.Finding.from_document(entry))
    assert "\n" not in text
    assert text == ("Finding(viscous_friction, added in the motor: Bm = 0.000152 N.m.s/rad (95 % 0.00013 to "
                    "0.000173 N.m.s/rad); held-out RMS 0.13 -> 0.0123 N.m; confidence 1.00)")
