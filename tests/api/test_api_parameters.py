"""`hdjoint.Parameters`: the table's defaults, units and descriptions, dict-like
access checked against the ranges, partial and documented files read back as
the same set, and the values a user states kept apart from the defaults."""
import json

import pytest

import hdjoint
from hdjoint.io import parameters as table_io


def test_defaults_units_and_descriptions_come_from_the_table():
    p = hdjoint.Parameters()
    table = table_io.table()
    assert list(p) == list(table) and len(p) == len(table)
    assert dict(p) == table_io.defaults()
    assert p.unit("Kt") == table["Kt"].unit and p.description("Kt") == table["Kt"].description
    assert p.range("Kt") == (table["Kt"].min, table["Kt"].max)
    assert p.stated == {} and p.changed() == {}


def test_setting_is_checked_and_nothing_is_set_when_refused():
    p = hdjoint.Parameters()
    p["Kt"] = 0.05
    with pytest.raises(hdjoint.ParameterError, match="outside its valid range"):
        p.update({"Jm": 1e-5, "Kt": -1.0})
    assert p.stated == {"Kt": 0.05} and p["Jm"] == table_io.defaults()["Jm"]
    with pytest.raises(hdjoint.ParameterError, match="unknown parameter 'nope'"):
        p["nope"] = 1.0
    with pytest.raises(KeyError):
        p["nope"]
    p.reset("Kt")
    assert p.stated == {} and p["Kt"] == table_io.defaults()["Kt"]


def test_a_partial_file_round_trips_with_its_statements(tmp_path):
    p = hdjoint.Parameters({"Kt": 0.05, "Ts": 2e-3}, tolerance={"Kt": 0.2}, accuracy=0.5,
                           sensor_noise={"i_m": 0.004})
    p.save(tmp_path / "p.json")
    written = json.loads((tmp_path / "p.json").read_text())
    assert written == {"Kt": 0.05, "Ts": 2e-3, "tolerance": {"Kt": 0.2}, "accuracy": 0.5,
                       "sensor_noise": {"i_m": 0.004}}
    q = hdjoint.Parameters.load(tmp_path / "p.json")
    assert q == p and q.stated == {"Kt": 0.05, "Ts": 2e-3}
    assert table_io.load(tmp_path / "p.json") == q.to_dict()  # as --params reads it


def test_a_documented_file_reads_back_as_the_same_set(tmp_path):
    p = hdjoint.Parameters({"Kt": 0.05}, tolerance={"Kt": 0.2})
    p.save(tmp_path / "full.json", documented=True)
    q = hdjoint.Parameters.load(tmp_path / "full.json")
    assert q.to_dict() == p.to_dict() and q.tolerance["Kt"] == 0.2
    doc = json.loads((tmp_path / "full.json").read_text())["documentation"]
    assert doc["Kt"]["unit"] == "N.m/A" and doc["Kt"]["description"]


def test_repr_names_the_stated_values_in_units():
    p = hdjoint.Parameters({"Kt": 0.05})
    assert repr(p) == f"Parameters(Kt = 0.05 N.m/A; the other {len(p) - 1} at their defaults)"
    assert "<table>" in p._repr_html_()
