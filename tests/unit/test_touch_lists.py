"""The touch lists of docs/extending.md stay true.

A new estimator output is a row of src/hdjoint/estimator_signals.def, the
line that computes it and its test: no Python module or test may keep its own
list of the estimator's outputs (a hand-kept list is a fourth file to touch,
and goes stale silently). The contract's own required names are the one
exception (tests/fmu/test_fmu_validation.py's CONTRACT).

A new hypothesis is one file in hdjoint/diagnosis/effects/ (and its test,
tests/diagnosis/test_effect_plugin.py shows one end to end): no module of
the diagnosis outside that folder may name an effect ID."""
import ast
from pathlib import Path

from hdjoint import _core
from hdjoint.diagnosis.effects import EFFECTS

ROOT = Path(__file__).resolve().parents[2]
PACKAGE = ROOT / "python" / "hdjoint"
ESTIMATOR_OUTPUTS = {r["name"] for r in _core.fmu_signals()["JointTorqueEstimator"] if r["kind"] == "output"}
CONTRACT_TEST = ROOT / "tests" / "fmu" / "test_fmu_validation.py"


def _string_collections(path: Path):
    """Each list, tuple, set or dict literal of the file with the strings it holds, and its line."""
    for node in ast.walk(ast.parse(path.read_text())):
        items = (node.keys if isinstance(node, ast.Dict) else node.elts
                 if isinstance(node, (ast.List, ast.Tuple, ast.Set)) else None)
        if items:
            yield node.lineno, {x.value for x in items if isinstance(x, ast.Constant) and isinstance(x.value, str)}


def _lists_the_outputs(strings: set[str]) -> bool:
    """All the estimator's outputs, or all but one (a list a new output would have to join)."""
    return len(strings & ESTIMATOR_OUTPUTS) >= len(ESTIMATOR_OUTPUTS) - 1


def hand_kept_output_lists(paths) -> list[str]:
    return [f"{p.relative_to(ROOT)}:{line}" for p in paths if p != CONTRACT_TEST
            for line, strings in _string_collections(p) if _lists_the_outputs(strings)]


def test_no_module_or_test_keeps_its_own_list_of_the_estimators_outputs():
    paths = [*PACKAGE.rglob("*.py"), *(ROOT / "tests").rglob("*.py")]
    assert hand_kept_output_lists(paths) == []


def test_the_scan_finds_a_hand_kept_list(tmp_path):
    stale = tmp_path / "stale.py"
    stale.write_text(f"COLUMNS = {['time', *sorted(ESTIMATOR_OUTPUTS)][:-1]!r}\n")
    assert [line for line, s in _string_collections(stale) if _lists_the_outputs(s)] == [1]


def _effect_ids_named(path: Path) -> set[str]:
    return {node.value for node in ast.walk(ast.parse(path.read_text()))
            if isinstance(node, ast.Constant) and node.value in EFFECTS}


def test_no_module_outside_the_effects_folder_names_an_effect():
    effects_folder = PACKAGE / "diagnosis" / "effects"
    named = {str(p.relative_to(ROOT)): ids for p in (PACKAGE / "diagnosis").rglob("*.py")
             if not p.is_relative_to(effects_folder) and (ids := _effect_ids_named(p))}
    assert named == {}
