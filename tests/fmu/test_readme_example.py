"""The README's fmpy example runs as written, on both FMI versions: one
output row per sample (a master that took the FMU's own step would give far
fewer), the torque hdjoint's own FMU runner computes sample by sample, and
FMI 3.0 equal to FMI 2.0."""
from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from hdjoint.fmu import experiments
from hdjoint.io import parameters
from hdjoint.fmu.runner import run_estimator_fmu
from hdjoint.io.recording import read_recording, write_recording

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


def test_readme_example_runs_as_written_on_both_fmi_versions(paper_csv, monkeypatch):
    folder, rec = paper_csv
    results = [run_snippet(folder, monkeypatch, fmi) for fmi in (2, 3)]
    written = read_recording(str(folder / "paper.csv"))
    expected = run_estimator_fmu(written.time, written.i_m, written.theta_m, written.theta_l,
                                 parameters.for_estimator(parameters.defaults()))
    for result in results:
        assert len(result) == len(rec.time)  # one row per 1 ms sample
        np.testing.assert_allclose(result["time"], rec.time, atol=1e-9)
        for name in ("tau_ukf", "tau_hat"):
            # fmpy's row at t holds the outputs of the step that ends at t: the sample before.
            np.testing.assert_allclose(result[name][1:], expected[name][:-1], rtol=0, atol=1e-9)
    for name in ("tau_ukf", "tau_hat"):
        assert np.array_equal(results[0][name], results[1][name])
