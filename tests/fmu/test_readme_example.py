"""The README's fmpy example runs as written, on both FMI versions, and its
rows are `hdjoint estimate`'s: at equal time stamps the same tau_ukf and
tau_hat. An output read at a communication point t describes the last sample
the step ran, t - Ts (fmpy records it at t, after the step from t - Ts), and
the example says so and shifts its rows; one output row per sample (a master
that took the FMU's own step would give far fewer); FMI 3.0 equal to FMI 2.0."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from hdjoint.app.cli import main
from hdjoint.fmu import experiments
from hdjoint.io.recording import write_recording

README = Path(__file__).resolve().parents[2] / "README.md"


def readme_snippet() -> str:
    blocks = re.findall(r"```python\n(.*?)```", README.read_text(), re.S)
    snippet = next(b for b in blocks if "simulate_fmu" in b and "JointTorqueEstimator" in b)
    assert 'fmu_path("JointTorqueEstimator")' in snippet
    return snippet


@pytest.fixture(scope="module")
def paper_csv(tmp_path_factory):
    folder = tmp_path_factory.mktemp("readme")
    rec = experiments.run("paper", duration=3.0)
    write_recording(str(folder / "paper.csv"), rec)
    return folder, rec


def run_snippet(folder, monkeypatch, fmi):
    code = readme_snippet()
    if fmi == 3:  # the same lines, the FMI 3.0 twin
        code = code.replace('fmu_path("JointTorqueEstimator")', 'fmu_path("JointTorqueEstimator", 3)')
    monkeypatch.chdir(folder)
    scope: dict = {}
    exec(compile(code, str(README), "exec"), scope)
    return scope["result"]


def test_readme_example_gives_hdjoint_estimates_rows_at_their_time_stamps(paper_csv, monkeypatch, capsys):
    folder, rec = paper_csv
    results = [run_snippet(folder, monkeypatch, fmi) for fmi in (2, 3)]
    assert main(["estimate", str(folder / "paper.csv"), "-o", str(folder / "est.csv")]) == 0, capsys.readouterr().err
    expected = np.genfromtxt(folder / "est.csv", delimiter=",", names=True)
    for result in results:
        assert len(result) == len(rec.time)  # one row per 1 ms sample, every sample
        # equal time stamps: the same instants, to the time column's round-off
        np.testing.assert_allclose(result["time"], expected["time"], rtol=0, atol=1e-9)
        for name in ("tau_ukf", "tau_hat"):
            np.testing.assert_allclose(result[name], expected[name], rtol=0, atol=1e-9)
    for name in ("tau_ukf", "tau_hat"):
        assert np.array_equal(results[0][name], results[1][name])


def test_the_readme_says_which_instant_an_output_describes():
    text = README.read_text()
    assert "communication point t describe" in text and "t - Ts" in text


@pytest.mark.parametrize("fmi", (2, 3))
def test_the_fmus_documentation_says_which_instant_an_output_describes(fmi):
    import zipfile
    from hdjoint.fmu.shipped import fmu_path
    with zipfile.ZipFile(fmu_path("JointTorqueEstimator", fmi)) as z:
        html = z.read("documentation/index.html").decode("utf-8")
    assert "<h2>Timing</h2>" in html and "describe the sample at <code>t - Ts</code>" in html
