"""The intended workflow (docs/estimators.md): diagnose a bench recording,
then estimate in use with the corrected parameter file, unchanged
(`hdjoint diagnose bench.csv --out d/` then
`hdjoint estimate run.csv --params d/params.json`). The case is "the model
is wrong": the paper's approximation for the wave generator load, which the
joint does not follow."""
import dataclasses

import numpy as np
import pytest

from hdjoint.app import cli
from hdjoint.io import parameters
from hdjoint.fmu.concealed_effects import CASES, nominal_for, record
from hdjoint.estimation.metrics import error_figures
from hdjoint.io.recording import write_recording


@pytest.mark.slow
def test_diagnose_then_estimate_with_the_written_parameter_file(tmp_path):
    case = next(c for c in CASES if c.present == ("wave_generator_load",))
    bench = record(case, duration=15.0)
    run = record(dataclasses.replace(case, seed=23), duration=10.0)  # in use: other noise, never diagnosed
    write_recording(tmp_path / "bench.csv", bench)
    write_recording(tmp_path / "run.csv", run)
    parameters.save(tmp_path / "nominal.json", nominal_for(case))

    assert cli.main(["diagnose", str(tmp_path / "bench.csv"), "--params", str(tmp_path / "nominal.json"),
                     "--out", str(tmp_path / "d")]) == 0
    errors = {}
    for label, params in (("nominal", tmp_path / "nominal.json"), ("diagnosed", tmp_path / "d" / "params.json")):
        out = tmp_path / f"est_{label}.csv"
        assert cli.main(["estimate", str(tmp_path / "run.csv"), "--params", str(params), "--smooth",
                         "-o", str(out)]) == 0
        est = np.genfromtxt(out, delimiter=",", names=True)
        truth = run.extra["tau_joint"]
        errors[label] = {n: error_figures(est[n], truth).rms for n in ("tau_compliance", "tau_hat", "tau_smooth")}
        assert np.all(np.isfinite(est["tau_smooth_std"]))
    assert parameters.load(tmp_path / "d" / "params.json")["wg_load"] == pytest.approx(1.0, abs=0.2)
    for name in ("tau_compliance", "tau_hat", "tau_smooth"):
        assert errors["diagnosed"][name] < 0.7 * errors["nominal"][name], (name, errors)
