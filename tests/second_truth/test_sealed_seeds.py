"""Tune apart, score sealed (issue 53, goal 2): the rows a results file reports
from the second truth come from its sealed seeds only, never from a seed any
choice was made on, and the held-out family is named where it was scored."""
import json
from pathlib import Path

from second_truth.cases import SEALED_SEEDS, TUNING_SEEDS
from second_truth.forms import HELD_OUT

RESULTS = Path(__file__).resolve().parents[2] / "docs" / "results"


def reported_seeds(path: Path) -> set[int]:
    return {json.loads(line)["seed"] for line in path.read_text().splitlines() if line.strip()}


def test_the_seed_sets_are_apart():
    assert not set(TUNING_SEEDS) & set(SEALED_SEEDS)


def test_reported_rows_share_no_seed_with_the_tuning_rows():
    rows = sorted(RESULTS.glob("*second_truth*.jsonl"))
    assert rows, "no results from the second truth"
    for path in rows:
        seeds = reported_seeds(path)
        assert seeds, path.name
        assert not seeds & set(TUNING_SEEDS), f"{path.name} reports tuning seeds {sorted(seeds & set(TUNING_SEEDS))}"
        assert seeds <= set(SEALED_SEEDS), f"{path.name} reports seeds outside the sealed set"


def test_the_checker_sees_a_tuning_seed(tmp_path):
    """The test itself: a file reporting a tuning seed is caught."""
    bad = tmp_path / "x_second_truth.jsonl"
    bad.write_text(json.dumps({"seed": min(TUNING_SEEDS)}) + "\n" + json.dumps({"seed": min(SEALED_SEEDS)}) + "\n")
    assert reported_seeds(bad) & set(TUNING_SEEDS)


def test_the_held_out_family_is_named_in_the_table():
    table = (RESULTS / "diagnosis_second_truth.md").read_text()
    for family in HELD_OUT:
        assert f"{family} (held out" in table
