"""`hdjoint diagnose`: the contract's outputs, and bad input refused with a
clear message and nothing written."""
import dataclasses
import json
import xml.etree.ElementTree as ET

import numpy as np
import pytest

from hdjoint.app import cli
from hdjoint.io import parameters
from hdjoint.fmu.concealed_effects import CASES, nominal_for, record
from hdjoint.diagnosis.model.prepare import DiagnosisError
from hdjoint.diagnosis.pipeline import diagnose
from hdjoint.fmu.runner import run_estimator_fmu
from hdjoint.io.recording import write_recording

pytestmark = pytest.mark.slow  # whole `hdjoint diagnose` runs

EFFECT_IDS = {"kinematic_error", "wave_generator_compliance", "stiffness_nonlinearity", "coulomb_friction",
              "stribeck_friction", "viscous_friction", "hysteresis", "backlash", "cogging", "time_delay",
              "thermal_drift", "gravity_load", "link_friction", "wave_generator_load"}


@pytest.fixture(scope="module")
def gravity_case(tmp_path_factory):
    case = next(c for c in CASES if c.present == ("gravity_load",))
    d = tmp_path_factory.mktemp("gravity")
    write_recording(d / "rec.csv", record(case, duration=12.0))
    # Another recording of the same joint, other noise: never fitted, only checked.
    write_recording(d / "other.csv", record(dataclasses.replace(case, seed=11), duration=8.0))
    parameters.save(d / "nominal.json", nominal_for(case))
    assert cli.main(["diagnose", str(d / "rec.csv"), "--params", str(d / "nominal.json"), "--out", str(d / "out"),
                     "--validate", str(d / "other.csv")]) == 0
    return d


def test_outputs_follow_the_contract(gravity_case):
    out = gravity_case / "out"
    doc = json.loads((out / "findings.json").read_text())
    assert doc["verdict"] in ("missing_physics", "consistent", "unexplained")
    for f in doc["findings"]:
        assert f["effect"] in EFFECT_IDS
        assert {"where", "evidence", "parameters", "fit"} <= set(f)
        assert {"rms_before", "rms_after", "holdout_rms_before", "holdout_rms_after"} <= set(f["fit"])
    # params.json is a full, valid parameter set equal to findings' params; .ssv names the same values.
    params = parameters.load(out / "params.json")
    assert params == pytest.approx(doc["params"])
    ssv = ET.parse(out / "params.ssv").getroot()
    names = {p.get("name") for p in ssv.iter() if p.tag.endswith("Parameter")}
    assert names == set(doc["params"])
    assert (out / "report.html").read_text().startswith("<!DOCTYPE html>")


def test_gravity_load_is_found_in_the_link_and_the_corrected_model_fits_held_out_data(gravity_case):
    doc = json.loads((gravity_case / "out" / "findings.json").read_text())
    assert doc["verdict"] == "missing_physics"
    first = doc["findings"][0]
    assert first["effect"] == "gravity_load" and first["where"]["part"] == "link"
    assert first["fit"]["holdout_rms_after"] < 0.5 * first["fit"]["holdout_rms_before"]
    assert doc["params"]["mgl"] == pytest.approx(5.0, rel=0.1)  # the simulated joint's gravity torque


def test_the_corrected_model_fits_a_recording_it_never_saw(gravity_case):
    doc = json.loads((gravity_case / "out" / "findings.json").read_text())
    (entry,) = doc["validation"]
    assert entry["path"].endswith("other.csv")
    link = entry["channels"]["link"]
    # Gravity is in the link channel: without it the link residual is the
    # whole mgl*sin(theta_l); with it, noise.
    assert link["corrected"]["rms"] < 0.2 * link["calibrated"]["rms"]
    for row in entry["channels"].values():
        assert row["corrected"]["rms"] <= 1.05 * row["calibrated"]["rms"]
    est = entry["estimator"]
    assert est["corrected"]["tau_compliance"]["rms"] <= est["nominal"]["tau_compliance"]["rms"]
    page = (gravity_case / "out" / "report.html").read_text()
    assert "Other recordings (never fitted)" in page
    # What belongs to the other recording is placed on it, and its operating range is compared.
    assert set(entry["current_alignment"]) == {"nominal", "calibrated", "corrected"}
    assert {q["quantity"] for q in entry["extrapolation"]} == {"motor speed", "motor current", "link angle"}
    assert "the current acting at each encoder sample is the one logged" in page


def test_a_malformed_validation_recording_is_refused_before_any_work(gravity_case, tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("time,i_m,theta_m,theta_l\n0,0,0,0\n0.001,0,x,0\n")
    out = tmp_path / "out"
    assert cli.main(["diagnose", str(gravity_case / "rec.csv"), "--out", str(out), "--validate", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "bad.csv" in err and "line 3" in err and "theta_m" in err
    assert not out.exists()


def test_corrected_parameters_run_in_the_estimator_fmu(gravity_case):
    from hdjoint.io.recording import read_recording
    rec = read_recording(gravity_case / "rec.csv")
    params = parameters.for_estimator(parameters.load(gravity_case / "out" / "params.json"))
    est = run_estimator_fmu(rec.time[:500], rec.i_m[:500], rec.theta_m[:500], rec.theta_l[:500], params)
    assert np.all(np.isfinite(est["tau_ukf"]))


def test_too_short_a_recording_is_refused(tmp_path):
    case = CASES[0]
    rec = record(case, duration=1.0)
    with pytest.raises(DiagnosisError, match="too short"):
        diagnose(rec, nominal_for(case))


def _with_gap(duration=3.0):
    """A control recording with 0.2 s of rows missing after t = 0.999 s."""
    case = CASES[0]
    rec = record(case, duration=duration)
    keep = np.ones(len(rec), bool)
    keep[1000:1200] = False
    for name in ("time", "i_m", "theta_m", "theta_l", "tau_sensor"):
        setattr(rec, name, getattr(rec, name)[keep])
    rec.extra = {}
    return case, rec


def test_a_gap_is_refused_naming_time_and_line():
    case, rec = _with_gap()
    with pytest.raises(DiagnosisError, match=r"gap of 0\.201 s after t = 0\.999 s \(line 1001\)"):
        diagnose(rec, nominal_for(case))


def test_the_command_refuses_a_gap_and_writes_nothing(tmp_path):
    _, rec = _with_gap()
    write_recording(tmp_path / "gap.csv", rec)
    assert cli.main(["diagnose", str(tmp_path / "gap.csv"), "--out", str(tmp_path / "out")]) == 2
    assert not (tmp_path / "out").exists()


def test_a_malformed_recording_writes_nothing(tmp_path, capsys):
    (tmp_path / "bad.csv").write_text("time,i_m,theta_m,theta_l\n0,0,0,0\n0.001,x,0,0\n")
    code = cli.main(["diagnose", str(tmp_path / "bad.csv"), "--out", str(tmp_path / "out")])
    assert code == 2
    err = capsys.readouterr().err
    assert "bad.csv" in err and "line 3" in err and "i_m" in err
    assert not (tmp_path / "out").exists()


def test_effects_without_excitation_are_reported_not_testable():
    case = CASES[0]
    rec = record(case, duration=6.0)  # shorter than thermal drift needs
    _, doc = diagnose(rec, nominal_for(case))
    reasons = {n["effect"]: n["reason"] for n in doc["not_testable"]}
    assert "thermal_drift" in reasons and "not testable on this recording" in reasons["thermal_drift"]


def test_hypotheses_fitted_side_by_side_give_the_same_diagnosis():
    case = next(c for c in CASES if c.present == ("gravity_load",))
    rec = record(case, duration=6.0)
    docs = []
    for workers in (1, 2):
        _, doc = diagnose(rec, nominal_for(case), workers=workers)
        doc.pop("seconds")
        docs.append(json.dumps(doc, sort_keys=True, default=str))
    assert docs[0] == docs[1]
