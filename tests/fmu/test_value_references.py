"""A variable keeps its value reference from release to release: SSP
systems, master scripts and saved parameter maps address variables by it.
tests/data/value_references.json holds each shipped FMU's references as
released; a variable may be added, none may move or vanish. (A parameter
inserted mid-table in parameter_table.def shifted every later one's.)"""
import json
from pathlib import Path

import pytest
from fmpy import read_model_description

from hdjoint.fmu.shipped import fmu_path

RELEASED = json.loads((Path(__file__).resolve().parents[1] / "data" / "value_references.json").read_text())


@pytest.mark.parametrize("name", sorted(RELEASED))
def test_no_released_value_reference_moves(name):
    built = {v.name: int(v.valueReference) for v in read_model_description(str(fmu_path(name))).modelVariables}
    moved = {n: (vr, built.get(n)) for n, vr in RELEASED[name].items() if built.get(n) != vr}
    assert not moved, f"{name}: value references moved or vanished (released, built): {moved}"
