"""The fleet's inputs, rows and trend test, without a cluster."""
import json
import math

import numpy as np
import pytest
from hdjoint.fleet import rows, trend
from hdjoint.fleet.inputs import glob_to_regex, plan
from hdjoint.jobs.inputs import UserError


@pytest.mark.parametrize("pattern, path, hit", [
    ("robot3/j2/*.csv", "robot3/j2/a.csv", True),
    ("robot3/j2/*.csv", "robot3/j2/x/a.csv", False),   # * stays in its folder
    ("robot3/**/*.csv", "robot3/j2/x/a.csv", True),
    ("robot3/**/*.csv", "robot3/a.csv", True),
    ("r?/[!b]*.csv", "r1/a.csv", True),
    ("r?/[!b]*.csv", "r1/b.csv", False),
])
def test_glob_patterns(pattern, path, hit):
    assert bool(glob_to_regex(pattern).match(path)) is hit


@pytest.fixture
def tree(tmp_path):
    for rel in ("logs/r1/j1/2026-01-01.csv", "logs/r1/j1/2026-01-02.csv", "logs/r1/j2/2026-01-01.csv"):
        (tmp_path / rel).parent.mkdir(parents=True, exist_ok=True)
        (tmp_path / rel).write_text("time,i_m,theta_m,theta_l\n")
    (tmp_path / "p").mkdir()
    (tmp_path / "p" / "j1.json").write_text('{"Fc": 0.01}')
    (tmp_path / "p" / "all.json").write_text("{}")
    return tmp_path


def test_first_matching_pattern_wins_and_names_the_joint(tree):
    (tree / "map.json").write_text(json.dumps({"logs/r1/j1/*.csv": "p/j1.json", "logs/**/*.csv": "p/all.json"}))
    jobs = plan([str(tree / "logs/**/*.csv")], str(tree / "map.json"), None)
    assert [(j.joint, j.folder, j.params.endswith("j1.json")) for j in jobs] == [
        ("logs/r1/j1/*.csv", "logs/r1/j1/csv", True), ("logs/r1/j1/*.csv", "logs/r1/j1/csv", True),
        ("logs/**/*.csv", "logs/csv", False)]


def test_joint_pattern_reads_joint_and_date(tree):
    (tree / "map.json").write_text(json.dumps({"logs/**/*.csv": "p/all.json"}))
    jobs = plan([str(tree / "logs/**/*.csv")], str(tree / "map.json"),
                r"logs/(?P<joint>r\d+/j\d+)/(?P<date>[\d-]+)\.csv")
    assert [(j.joint, j.date, j.name) for j in jobs] == [
        ("r1/j1", "2026-01-01", "2026-01-01"), ("r1/j1", "2026-01-02", "2026-01-02"),
        ("r1/j2", "2026-01-01", "2026-01-01")]


@pytest.mark.parametrize("setup, args, message", [
    ({"logs/r1/j1/*.csv": "p/j1.json"}, (None,), "no pattern of the params map matches"),
    ({"logs/**/*.csv": "p/missing.json"}, (None,), "parameter file p/missing.json not found"),
    ({"logs/**/*.csv": "p/all.json"}, (r"(?P<who>x)",), "named group (?P<joint>"),
    ({"logs/**/*.csv": "p/all.json"}, (r"(",), "not a valid regex"),
    ([], (None,), "non-empty JSON object"),
])
def test_bad_inputs_are_named(tree, setup, args, message):
    (tree / "map.json").write_text(json.dumps(setup))
    with pytest.raises(UserError, match=message.replace("(", r"\(").replace("?", r"\?")):
        plan([str(tree / "logs/**/*.csv")], str(tree / "map.json"), *args)


def test_no_recordings_is_an_error(tmp_path):
    with pytest.raises(UserError, match="no recordings match"):
        plan([str(tmp_path / "*.csv")], None, None)


def test_rows_read_todays_and_the_agreed_findings_schema():
    today = {"verdict": "missing_physics", "params": {"Fc": 0.02, "Kf": 5e4},
             "findings": [{"effect": "backlash", "confidence": 0.9, "parameters": {"backlash": 2e-5}}],
             "calibration": {"Kf": {"nominal": 5.2e4, "calibrated": 5e4}}}
    agreed = {"verdict": "missing_physics", "params": {"Fc": 0.02, "Kf": 5e4},
              "findings": [{"effect": "coulomb_friction", "kind": "resized", "p_value": 1e-4, "confidence": 0.97,
                            "parameters": {"Fc": {"nominal": 0.01, "estimate": 0.02, "lo": 0.018, "hi": 0.022}}}],
              "calibration": {"Kf": {"nominal": 5.2e4, "estimate": 5e4, "lo": 4.9e4, "hi": 5.1e4}}}
    a, b = rows.diagnosis_row(today), rows.diagnosis_row(agreed)
    assert a["findings"][0]["kind"] == "" and math.isnan(a["findings"][0]["p_value"])
    assert math.isnan(a["param.Kf.lo"]) and a["param.Kf"] == 5e4
    assert b["findings"][0] == {"effect": "coulomb_friction", "kind": "resized", "confidence": 0.97, "p_value": 1e-4}
    assert (b["param.Fc.lo"], b["param.Fc.hi"], b["param.Kf.lo"]) == (0.018, 0.022, 4.9e4)
    table = rows.table([{"recording": "x", "status": "ok", **a}, {"recording": "y", "status": "failed",
                                                                   "error": "bad"}, {"recording": "z", **b}])
    assert table.num_rows == 3 and table.column("findings").to_pylist()[1] == []
    assert math.isnan(table.column("param.Fc.lo").to_pylist()[0])


def test_trend_false_alarm_rate_on_series_without_drift():
    # The slope test estimates the residual scale, so intervals wrong by a
    # common factor (0.3-3x here) keep the false-alarm rate at its nominal 5 %
    # (2000 series: +-3 binomial standard deviations is 3.5-6.5 %).
    rng = np.random.default_rng(5)
    days = np.arange(6, dtype=float)
    alarms = []
    for _ in range(2000):
        se = 0.05 * rng.uniform(0.5, 2.0, days.size)
        y = 1.0 + rng.normal(0.0, se)
        half = trend.INTERVAL_Z * se * rng.uniform(0.3, 3.0)
        alarms.append(trend.slope_test(days, y, y - half, y + half)[2] < trend.ALPHA)
    assert 0.035 < np.mean(alarms) < 0.065


def test_trend_finds_a_growing_parameter_and_ranks_its_joint_first():
    rng = np.random.default_rng(2)
    found = []
    for joint, growth in (("quiet", 0.0), ("drifting", 0.08), ("quiet2", 0.0)):
        for day in range(6):
            fc = 0.02 * (1 + growth * day) * (1 + 0.02 * rng.standard_normal())
            kf = 5e4 * (1 + 0.01 * rng.standard_normal())
            found.append({"joint": joint, "date": f"2026-01-0{day + 1}", "status": "ok", "param.Fc": fc,
                          "param.Kf": kf})
    ranked = trend.rank_joints(found)
    assert ranked[0].joint == "drifting" and ranked[0].drifting
    assert (ranked[0].effect, ranked[0].direction) == ("coulomb_friction", "growing")
    assert 0.3 < ranked[0].strongest.change < 0.5


def test_a_significant_but_tiny_trend_is_not_a_drift():
    # +2 % over the period at p << 0.05: below the 10 % default, and below a
    # stated tolerance; with a tolerance of 1 % of the value it is a drift.
    def joint(tol=None):
        found = []
        for day in range(6):
            row = {"joint": "j", "date": f"2026-01-0{day + 1}", "status": "ok",
                   "param.Bm": 3e-5 * (1 + 0.004 * day + 1e-4 * (-1) ** day)}
            if tol is not None:
                row["param.Bm.tol"] = tol
            found.append(row)
        return trend.joint_trend("j", found)
    tiny = joint()
    assert tiny.strongest.p_value < 1e-4 and not tiny.drifting
    assert not joint(tol=3e-6).drifting and joint(tol=3e-7).drifting


def test_the_command_line_names_bad_input_in_one_line(tree, capsys):
    from hdjoint.app import cli
    (tree / "map.json").write_text(json.dumps({"logs/r1/j1/*.csv": "p/j1.json"}))
    code = cli.main(["fleet", "estimate", str(tree / "logs/**/*.csv"), "--params-map", str(tree / "map.json"),
                     "--out", str(tree / "out")])
    err = capsys.readouterr().err.strip()
    assert code == 2 and len(err.splitlines()) == 1
    assert err.startswith("hdjoint fleet:") and "2026-01-01.csv: no pattern of the params map matches" in err
    assert not (tree / "out").exists()


def test_kinematic_amplitudes_split_motor_and_link_orders_with_intervals():
    row = {"param.aw1": 3e-5, "param.bw1": 4e-5, "param.aw2": 0.0, "param.bw2": 0.0, "param.ke_m1_a": 0.0,
           "param.ke_m1_b": 0.0, "param.ke_m1_order": 3.0, "param.al1": 1e-4, "param.bl1": -1e-4}
    value, lo, hi = trend.quantity(row, trend.KINEMATIC_MOTOR)
    assert value == pytest.approx(5e-5 / math.sqrt(2)) and math.isnan(lo)
    assert trend.quantity(row, trend.KINEMATIC_LINK)[0] == pytest.approx(1e-4)
    for name in ("aw1", "bw1", "aw2", "bw2", "ke_m1_a", "ke_m1_b"):
        row[f"param.{name}.lo"], row[f"param.{name}.hi"] = row[f"param.{name}"] - 2e-6, row[f"param.{name}"] + 2e-6
    value, lo, hi = trend.quantity(row, trend.KINEMATIC_MOTOR)
    # d(amplitude)/d(coefficient) = c / (2 * amplitude): only aw1 and bw1 contribute, each 2e-6 wide.
    assert hi - value == pytest.approx(2e-6 * math.hypot(3e-5, 4e-5) / (2 * value))


def test_progress_line_counts_done_failed_remaining_with_an_eta():
    import io

    from hdjoint.fleet.run import Progress
    stream = io.StringIO()
    progress = Progress(10, 2, stream=stream)
    progress.update(failed=False)
    progress.update(failed=True, final=True)
    line = stream.getvalue().strip().splitlines()[-1]
    assert "3/10 done (2 earlier), 1 failed, 6 remaining, ETA " in line and "ETA ?" not in line


def test_progress_writes_to_the_stderr_of_its_run():
    """Its stream defaulted to sys.stderr as bound when hdjoint.fleet.run was first imported: a
    first import inside a test capturing stderr left every later fleet run in that process
    writing to a closed capture ("I/O operation on closed file", the fleet diagnosis tests failing
    after the refusal tests)."""
    import contextlib
    import io

    from hdjoint.fleet.run import Progress
    with contextlib.redirect_stderr(io.StringIO()) as now:
        Progress(1, 0).update(failed=False, final=True)
    assert "[fleet]" in now.getvalue()
