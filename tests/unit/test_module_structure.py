"""The package's modules depend on each other one way: the command line and
the demo share jobs.py, and neither imports the other, not even lazily
inside a function."""
import ast
import importlib
import inspect


def _imported_modules(module: str) -> set[str]:
    tree = ast.parse(inspect.getsource(importlib.import_module(module)))
    found = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.ImportFrom):
            found.add(("." * node.level) + (node.module or ""))
        elif isinstance(node, ast.Import):
            found.update(alias.name for alias in node.names)
    return found


def test_demo_does_not_import_the_command_line():
    assert not {".cli", "hdjoint.cli"} & _imported_modules("hdjoint.demo")


def test_command_line_does_not_import_the_demo():
    assert not {".demo", "hdjoint.demo"} & _imported_modules("hdjoint.cli")


def test_one_conftest_for_the_whole_suite():
    # Test modules import shared names with `from conftest import ...`; a
    # second conftest.py in a subfolder would shadow the root one for the
    # whole session and break those imports whenever both are collected.
    from pathlib import Path
    tests = Path(__file__).resolve().parents[1]
    assert [p.relative_to(tests).as_posix() for p in tests.rglob("conftest.py")] == ["conftest.py"]
