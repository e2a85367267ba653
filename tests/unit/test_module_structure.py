"""The package's modules depend on each other one way: the command line and
the demo share jobs.py, and neither imports the other."""
import subprocess
import sys


def _imports_after(module: str) -> set[str]:
    code = f"import sys, {module}; print(' '.join(m for m in sys.modules if m.startswith('hdjoint')))"
    out = subprocess.run([sys.executable, "-c", code], check=True, capture_output=True, text=True).stdout
    return set(out.split())


def test_demo_does_not_import_the_command_line():
    assert "hdjoint.cli" not in _imports_after("hdjoint.demo")


def test_command_line_does_not_import_the_demo():
    assert "hdjoint.demo" not in _imports_after("hdjoint.cli")
