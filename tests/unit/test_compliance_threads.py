"""_core.compliance split over threads: where no loop or delay line carries
state each sample stands alone, and the split run gives the very numbers of
the whole one; with state it runs whole."""
import numpy as np
import pytest

from hdjoint import _core
from hdjoint.io import parameters


def _inputs(n=30000):
    t = np.arange(n) * 1e-3
    theta_l = 0.8 * np.sin(0.7 * t)
    current = 1.5 * np.sin(3.1 * t) + 0.2 * np.random.default_rng(5).standard_normal(n)
    return current, parameters.defaults()["N"] * theta_l + 2e-4 * np.sin(9.0 * t), theta_l


@pytest.mark.parametrize("changes", [{}, {"wg_load": 0.9}, {"hys_H": 0.4}, {"i_delay": 3e-3}],
                         ids=["paper", "loaded wave generator", "hysteresis (state)", "delay line (state)"])
def test_a_split_run_gives_the_numbers_of_a_whole_one(changes):
    native = parameters.for_estimator(dict(parameters.defaults(), **changes))
    whole = _core.compliance(native, *_inputs())
    for threads in (2, 3, 8):
        split = _core.compliance(native, *_inputs(), threads=threads)
        for name, values in whole.items():
            assert np.array_equal(values, split[name], equal_nan=True), (name, threads)


def test_a_short_run_and_a_bad_thread_count_run_whole():
    native = parameters.for_estimator(parameters.defaults())
    short = [x[:100] for x in _inputs()]
    assert np.array_equal(_core.compliance(native, *short, threads=4)["tau_compliance"],
                          _core.compliance(native, *short)["tau_compliance"], equal_nan=True)
    assert np.array_equal(_core.compliance(native, *_inputs(), threads=0)["tau_compliance"],
                          _core.compliance(native, *_inputs())["tau_compliance"], equal_nan=True)
