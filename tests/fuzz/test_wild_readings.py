"""Issue 56: both estimators survive readings no sensor could produce, in the
batch path and in the FMU of both FMI versions (the engine and what counts as
a finding: wild_readings.py). Fixed seeds; a longer run:
python benchmarks/fuzz_fmus.py --wild N."""
from __future__ import annotations

import pytest

from wild_readings import KINDS, campaign

pytestmark = pytest.mark.slow  # ~75 runs of a 1 s recording
SEEDS = range(24)


@pytest.fixture(scope="module")
def outcomes():
    return campaign(SEEDS)


def test_every_kind_of_wild_reading_is_tried_on_every_engine(outcomes):
    for engine in ("batch", "fmi2", "fmi3"):
        kinds = {o.scenario.kind for o in outcomes if o.engine == engine}
        assert kinds == set(KINDS) - ({"nan burst"} if engine != "batch" else set()), (engine, kinds)


def test_no_wild_reading_breaks_an_estimator(outcomes):
    found = [f"{o.engine}: {o.scenario.describe()}: {f}" for o in outcomes for f in o.findings]
    assert not found, "\n".join(found)
