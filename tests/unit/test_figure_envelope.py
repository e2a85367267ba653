"""io.figures.envelope: a long trace is drawn as each run's lowest and
highest sample, in time order, so the line covers what the whole trace
covers at a fraction of the points; gaps stay gaps."""
import numpy as np

from hdjoint.io.figures import envelope


def test_a_long_trace_keeps_its_extremes_its_order_and_its_gaps():
    t = np.arange(58001) * 1e-3
    y = np.sin(3.0 * t) + 0.05 * np.random.default_rng(1).standard_normal(t.size)
    y[20000:21000] = np.nan  # a logging gap
    x, v = envelope(t, y, 500)
    assert len(x) <= 1000 and np.all(np.diff(x) >= 0)
    assert np.nanmax(v) == np.nanmax(y) and np.nanmin(v) == np.nanmin(y)
    gap = (x >= t[20000]) & (x < t[21000])
    assert gap.any() and np.isnan(v[gap]).any(), "the gap was drawn over"
    # Every run's extremes are kept: the envelope of each run of the trace is the envelope drawn.
    run = -(-len(y) // 500)
    for start in range(0, len(y), 37 * run):
        part = y[start:start + run]
        if np.isfinite(part).any():
            assert np.nanmax(part) in v and np.nanmin(part) in v


def test_a_short_trace_is_drawn_as_it_is():
    t = np.arange(100.0)
    x, v = envelope(t, np.cos(t), 500)
    assert np.array_equal(x, t) and np.array_equal(v, np.cos(t))
