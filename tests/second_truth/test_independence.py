"""The second truth is written apart from the diagnosis: nothing in
benchmarks/second_truth imports hdjoint (the diagnosis or anything else),
the first truth (hdjoint_truth) or the tuning helpers."""
from __future__ import annotations

import ast
from pathlib import Path

PKG = Path(__file__).resolve().parents[2] / "benchmarks" / "second_truth"
FORBIDDEN = ("hdjoint", "hdjoint_truth", "tuning", "benchmarks.hdjoint_truth", "benchmarks.tuning")


def offending_imports(source: str) -> list[str]:
    bad = []
    for node in ast.walk(ast.parse(source)):
        names = []
        if isinstance(node, ast.Import):
            names = [a.name for a in node.names]
        elif isinstance(node, ast.ImportFrom) and node.level == 0 and node.module:
            names = [node.module] + [f"{node.module}.{a.name}" for a in node.names]
        elif isinstance(node, ast.Call) and getattr(node.func, "attr", getattr(node.func, "id", "")) in (
                "import_module", "__import__") and node.args and isinstance(node.args[0], ast.Constant):
            names = [str(node.args[0].value)]
        bad += [n for n in names if any(n == f or n.startswith(f + ".") for f in FORBIDDEN)]
    return bad


def test_checker_catches_forbidden_imports():
    assert offending_imports("import hdjoint.diagnosis.rules")
    assert offending_imports("from hdjoint.diagnosis import pipeline")
    assert offending_imports("from hdjoint_truth import joint")
    assert offending_imports("import tuning")
    assert offending_imports("import importlib\nimportlib.import_module('hdjoint.diagnosis')")
    assert not offending_imports("import numpy\nfrom .forms import base\nfrom scipy.integrate import solve_ivp")


def test_second_truth_imports_nothing_forbidden():
    files = sorted(PKG.rglob("*.py"))
    assert len(files) > 20
    for f in files:
        assert not offending_imports(f.read_text()), f
