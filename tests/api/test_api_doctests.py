"""The API's docstring examples run, as written, against the installed
package (doctest.testmod on each module of hdjoint.api and on hdjoint itself)."""
import doctest
import importlib

import pytest

FLAGS = doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE
QUICK = ("hdjoint", "hdjoint.api", "hdjoint.api.parameters", "hdjoint.api.results")


def run_examples(name: str) -> doctest.TestResults:
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=FLAGS, verbose=False)
    assert result.attempted > 0, f"{name} has no examples"
    return result


@pytest.mark.parametrize("name", QUICK)
def test_the_examples_run(name):
    assert run_examples(name).failed == 0


@pytest.mark.slow  # a simulation, estimates, a diagnosis and a calibration of a few seconds of data: ~10 s
def test_the_functions_examples_run():
    assert run_examples("hdjoint.api.functions").failed == 0


def test_import_hdjoint_stays_quick():
    """`import hdjoint` imports none of its layers; a name of the API imports it on first use."""
    import subprocess
    import sys
    code = ("import sys, hdjoint; before = sorted(m for m in sys.modules if m.startswith('hdjoint.'));"
            "hdjoint.Parameters; print(before, 'hdjoint.api' in sys.modules)")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[] True"
