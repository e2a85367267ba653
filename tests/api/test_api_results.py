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


def synthetic_diagnosis(tmp_path) -> "hdjoint.Diagnosis":
    """A folder as `hdjoint diagnose --out` writes it, with one finding and the estimators' figures."""
    import json
    doc = {"verdict": "missing_physics", "recording": {"path": "bench.csv"},
           "findings": [{"effect": "backlash", "kind": "added", "confidence": 0.97, "where": {"part": "gear"},
                         "parameters": {"backlash": 2e-5}, "intervals": {"backlash": [1.8e-5, 2.2e-5]},
                         "fit": {"holdout_rms_before": 0.185, "holdout_rms_after": 0.047}}],
           "unexplained": [], "calibration": {"Kt": {}, "Kf": {}}, "beyond_tolerance": ["Kf"],
           "estimator": {label: {"tau_compliance": {"rms": rms, "max": 2 * rms}, "tau_ukf": {"rms": rms, "max": rms}}
                         for label, rms in (("nominal", 0.2), ("corrected", 0.05))},
           "noise": {"motor": float("nan")}}
    (tmp_path / "findings.json").write_text(json.dumps(doc))
    hdjoint.Parameters({"backlash": 2e-5}).save(tmp_path / "params.json")
    (tmp_path / "report.html").write_text("<html>report</html>")
    return hdjoint.Diagnosis.load(tmp_path)


def test_a_diagnosis_reads_in_words_and_writes_its_files(tmp_path):
    import json
    d = synthetic_diagnosis(tmp_path)
    assert d.verdict == "missing_physics" and d.recordings == ["bench.csv"]
    assert d.corrected["backlash"] == 2e-5 and d.corrected.stated == {"backlash": 2e-5}
    assert repr(d).splitlines() == [
        "Diagnosis(bench.csv: missing_physics",
        "  Finding(backlash, added in the gear: backlash = 2e-05 rad (95 % 1.8e-05 to 2.2e-05 rad); held-out RMS "
        "0.185 -> 0.047 N.m; confidence 0.97)",
        "  .corrected: 2 parameters calibrated, beyond their tolerance: Kf)"]
    html = d._repr_html_()
    assert "verdict: missing_physics" in html and "backlash" in html and "<table>" in html
    assert json.loads(d.to_json())["noise"]["motor"] is None  # strict JSON, as findings.json
    assert d.report(tmp_path / "copy.html").read_text() == "<html>report</html>"


def test_a_diagnosis_plots_its_findings_and_estimators():
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    import tempfile
    from pathlib import Path
    with tempfile.TemporaryDirectory() as folder:
        fig = synthetic_diagnosis(Path(folder)).plot()
    assert isinstance(fig, Figure) and len(fig.axes) == 2
    assert fig.axes[0].get_title() == "verdict: missing_physics"
