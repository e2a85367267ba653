"""The second truth benchmark's scoring of findings.json (no diagnosis run)."""
from __future__ import annotations

import diagnosis_second_truth as bench

FAM = {"motor_friction": "lugre"}


def _rec(planted, **kw):
    return {"seed": 1, "control": not planted, "planted": [{"id": p} for p in planted], "families": FAM,
            "excitation": "chirp", "with_sensor": True, "truth_params": {"Kf": 17500.0},
            "forms": [{"role": "current_sensor", "params": {"delay": 1e-4, "tau_s": 2e-5}}], **kw}


def test_control_alarmed_only_when_not_consistent():
    assert not bench.score(_rec([]), {"verdict": "consistent", "findings": []})["alarmed"]
    assert bench.score(_rec([]), {"verdict": "unexplained", "findings": []})["alarmed"]
    assert bench.score(_rec([]), {"verdict": "missing_physics", "findings": [{"effect": "cogging"}]})["alarmed"]


def test_effect_named_first_or_anywhere():
    d = {"verdict": "missing_physics", "findings": [{"effect": "hysteresis", "kind": "added"},
                                                   {"effect": "backlash", "kind": "added"}]}
    assert bench.score(_rec(["hysteresis"]), d)["named_first"]
    r = bench.score(_rec(["backlash"]), d)
    assert not r["named_first"] and r["named_anywhere"]
    amb = {"verdict": "missing_physics", "findings": [{"effect": "hysteresis", "kind": "ambiguous",
                                                       "alternatives": ["backlash"]}]}
    assert bench.score(_rec(["backlash"]), amb)["named_anywhere"]
    assert not bench.score(_rec(["cogging"]), amb)["named_anywhere"]


def test_far_off_interval():
    f = {"effect": "stiffness_nonlinearity", "kind": "resized",
         "parameters": {"Kf": {"nominal": 7000, "estimate": 17000, "lo": 16000, "hi": 18000}}}
    r = bench.score(_rec(["kf_far_off"]), {"verdict": "missing_physics", "findings": [f]})
    assert r["resized"] and r["holds"]
    f["parameters"]["Kf"]["hi"] = 17400
    assert not bench.score(_rec(["kf_far_off"]), {"verdict": "missing_physics", "findings": [f]})["holds"]
    cal = {"verdict": "consistent", "findings": [], "calibration": {"Kf": {"estimate": 9000, "lo": 8000, "hi": 10000}}}
    r = bench.score(_rec(["kf_far_off"]), cal)
    assert not r["resized"] and not r["holds"] and r["kf_estimate"] == 9000


def test_report_counts():
    rows = [bench.score(_rec([]), {"verdict": "consistent", "findings": []}),
            bench.score(_rec([]), {"verdict": "unexplained", "findings": []})]
    text = bench.report(rows, "cmd", "abc")
    assert "| controls alarmed (verdict not `consistent`) | 1/2 |" in text
    assert "| motor_friction | lugre | 1/2 | - |" in text


def test_delay_found_beside_the_truth():
    d = {"verdict": "missing_physics", "findings": [{"effect": "time_delay", "kind": "added",
                                                     "parameters": {"i_delay": 0.0004}}]}
    r = bench.score(_rec([]), d)
    assert r["current_delay_truth"] == 1.2e-4 and r["i_delay_found"] == 0.0004
    assert "| 0.120 -> 0.400 |" in bench.report([r], "cmd", "abc")
