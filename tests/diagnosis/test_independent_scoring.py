"""How the independent benchmark scores a diagnosis: a look-alike set that
contains the effect or a resized finding counts as named; a control is a
false alarm unless `consistent`; closure needs the second recording consistent."""
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import diagnosis_independent as bench  # noqa: E402


def run(verdict, *findings, excitation="paper"):
    return {"verdict": verdict, "seconds": 10.0, "simulate_seconds": 5.0, "excitation": excitation,
            "findings": [dict(f, named=sorted(bench._named(f)), kind=f.get("kind", "added")) for f in findings]}


def row(case, present, *runs, seed=0):
    return {"case": case, "present": list(present), "seed": seed, "duration": 30.0, "runs": list(runs)}


def test_scoring_counts_lookalike_sets_and_resized_findings(tmp_path):
    ambiguous = {"effect": "backlash", "kind": "ambiguous",
                 "alternatives": [{"effect": "backlash"}, {"effect": "hysteresis"}]}
    rows = [
        row("hysteresis", ["hysteresis"], run("missing_physics", ambiguous), run("consistent")),
        row("kinematic", ["kinematic_error"], run("missing_physics", {"effect": "kinematic_error", "kind": "resized"}),
            run("unexplained")),
        row("viscous", ["viscous_friction"], run("missing_physics", {"effect": "time_delay"}), run("consistent")),
        row("control", [], run("consistent"), run("unexplained", excitation="sweep")),
    ]
    text = bench.write_table(rows, tmp_path / "table.md")
    assert "| single effect named first (added, resized or in a look-alike set) | 2/3 (67 %)" in text
    assert "| false alarms on controls (verdict not `consistent`) | 1/2 (50 %)" in text
    assert "2/3 (67 %); with every effect named on the first: 1/3 (33 %)" in text
    assert (tmp_path / "table.md").read_text() == text


def test_results_done_twice_count_once(tmp_path):
    import json
    path = tmp_path / "results.jsonl"
    first = row("control", [], run("consistent"))
    again = row("control", [], run("unexplained"))
    path.write_text(json.dumps(first) + "\n" + json.dumps(again) + "\n")
    assert bench.load_results(path) == [first]


def test_a_miss_the_diagnosis_said_it_cannot_tell_is_counted_apart(tmp_path):
    said = dict(run("consistent", excitation="sweep"), cannot_tell=["viscous_friction", "time_delay"])
    silent = dict(run("consistent"), cannot_tell=["time_delay"])
    rows = [row("viscous", ["viscous_friction"], said, seed=2), row("backlash", ["backlash"], silent),
            row("cogging", ["cogging"], run("missing_physics", {"effect": "cogging"}))]
    text = bench.write_table(rows, tmp_path / "table.md")
    assert "| single effect named first (added, resized or in a look-alike set) | 1/3 (33 %)" in text
    assert "said it cannot tell (`cannot_tell`) | 1/2 (50 %)" in text
    assert "s2 sweep: consistent, cannot tell viscous_friction |" in text


def test_how_often_a_control_carries_a_cannot_tell_caveat(tmp_path):
    rows = [row("control on paper", [], dict(run("consistent"), cannot_tell=["hysteresis"]),
                dict(run("consistent"), cannot_tell=[])),
            row("control on sweep", [], run("consistent"))]  # an older row: not counted
    text = bench.write_table(rows, tmp_path / "table.md")
    assert "| controls where `cannot_tell` names an effect (a `consistent` verdict's caveat) | 1/2 (50 %)" in text


def test_the_first_round_keeps_every_input_of_the_acceptance_rule():
    """So that another acceptance rule can be scored on the recorded rows without rerunning them."""
    tested = {"effect": "backlash", "held_out_gain": 0.1, "z": 2.05, "p_value": 0.03, "delta_bic": -741.0,
              "folds_improved": "12/13", "worst_channel_ratio": 0.98, "degenerate": "a dead zone", "accepted": False,
              "not an input": 1}
    doc = {"verdict": "consistent", "findings": [], "hypotheses_tested": [[tested]]}
    first = bench.summary(doc)["first_round"][0]
    assert first == {k: v for k, v in tested.items() if k != "not an input"}


def test_rows_are_grouped_by_the_engine_that_diagnosed_them():
    """A docs-only commit on top does not make another engine: rows carry the
    last commit that changed the engine, and older rows their HEAD."""
    rows = [dict(row("a", ["cogging"], seed=0), commit="docs1", engine="abc123"),
            dict(row("b", ["cogging"], seed=1), commit="docs2", engine="abc123"),
            dict(row("c", [], seed=0), commit="old999")]
    assert bench._engines(rows) == "abc123 (effects s0, effects s1); old999 (controls s0)"


def test_a_ripple_named_at_orders_the_truth_lacks_is_counted_apart(tmp_path):
    """Seed 0's kinematic error has link order 2 and motor order 4 beyond eq. (7)
    (hdjoint_truth.cases); a finding at link order 5 names the effect, not its orders."""
    case = "kinematic error (extra orders)"
    at = lambda *orders: {"effect": "kinematic_error", "orders": [list(o) for o in orders]}  # noqa: E731
    rows = [row(case, ["kinematic_error"], run("missing_physics", at(("theta_l", 5.0))), seed=0),
            row(case, ["kinematic_error"], run("missing_physics", at(("theta_l", 2.0), ("theta_m", 4.0))), seed=0),
            row(case, ["kinematic_error"], run("missing_physics", at(("theta_m", 4.0))), seed=0)]
    text = bench.write_table(rows, tmp_path / "table.md")
    assert "| single effect named first (added, resized or in a look-alike set) | 3/3 (100 %)" in text
    assert "| of those with ripples (kinematic error, cogging), named at the truth's orders only | 2/3 (67 %)" in text
    assert "kinematic_error (added; theta_l 5)" in text


def test_misses_are_counted_against_the_oracle_retest(tmp_path):
    """A miss effect_detectability.py could not show from the truth's own values
    counts as hidden; one it did not retest is said to be untested; a named
    effect is not a miss at all."""
    import json
    oracle_path = tmp_path / "oracle.jsonl"
    oracle_path.write_text("\n".join(json.dumps(r) for r in [
        {"case": "hysteresis", "seed": 0, "verdict": "not detectable"},  # old rows carry no "effect"
        {"case": "backlash", "seed": 2, "effect": "backlash", "verdict": "detectable"},
        {"case": "viscous friction", "seed": 0, "effect": "viscous_friction", "verdict": "not detectable"},
    ]) + "\n")
    rows = [
        row("hysteresis", ["hysteresis"], run("consistent")),
        row("backlash", ["backlash"], run("consistent"), seed=2),
        row("thermal drift", ["thermal_drift"], run("consistent")),
        row("viscous friction", ["viscous_friction"], run("missing_physics", {"effect": "viscous_friction"})),
    ]
    text = bench.write_table(rows, tmp_path / "table.md", oracle=bench.load_oracle(oracle_path))
    assert "cannot show either (effect_detectability.md) | 1/3 (33 %); 1 not retested |" in text


def test_an_effect_among_several_counts_as_accounted_for_only_where_the_oracle_cannot_show_it(tmp_path):
    pair = ["cogging", "time_delay"]
    rows = [row("two", pair, run("missing_physics", {"effect": "cogging"}), seed=0),
            row("two", pair, run("missing_physics", {"effect": "cogging"}), seed=1),
            row("two", pair, run("missing_physics", {"effect": "cogging"}, {"effect": "time_delay"}), seed=2)]
    oracle = {("two", 0, "time_delay"): "not detectable", ("two", 1, "time_delay"): "detectable"}
    text = bench.write_table(rows, tmp_path / "table.md", oracle=oracle)
    assert "| several effects: all named | 1/3 (33 %)" in text
    assert "cannot show either (effect_detectability.md) | 2/3 (67 %)" in text
