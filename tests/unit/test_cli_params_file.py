"""`hdjoint params --defaults -o joint.json` writes every parameter with its
unit, range, description and the diagnosis's tolerance, in a form `--params`
reads back as the same set (values and tolerances), and a unit changed in it
is refused."""
import json

from cli_helpers import assert_one_line_error, run_cli
from hdjoint.io import parameters


def test_defaults_round_trip_through_params(tmp_path, capsys):
    code, out, err = run_cli(capsys, "params", "--defaults", "-o", tmp_path / "joint.json")
    assert code == 0, err
    doc = json.loads((tmp_path / "joint.json").read_text())
    table = parameters.table()
    # Ts and the reading-time jitter stay the recording's (estimate takes them from it unless a file sets them)
    left_out = set(parameters.FROM_THE_RECORDING)
    assert left_out == {"Ts", "jsf_r_time"} and not left_out & set(doc)
    assert all("left_out" in doc["documentation"][n] for n in left_out)
    assert {n: doc[n] for n in table if n not in left_out} == {
        n: v for n, v in parameters.defaults().items() if n not in left_out}
    assert set(doc["documentation"]) == set(table)
    for name, info in table.items():
        entry = doc["documentation"][name]
        assert entry["unit"] == info.unit and entry["description"] == info.description
        assert entry["range"] == [info.min, info.max] and entry["prior"]
    lo, hi = parameters.TOLERANCE_RANGE  # a prior that is absolute only (relative 0) is in the documentation alone
    assert doc["tolerance"] == {n: i.tolerance_relative for n, i in table.items()
                                if i.calibrated() and lo <= i.tolerance_relative <= hi}
    assert "absolute" in doc["documentation"]["a0"]["prior"]
    assert isinstance(doc["about"], list) and doc["about"]
    # read back as --params reads it: the same values and the table's own tolerances
    assert parameters.load(tmp_path / "joint.json") == parameters.defaults()
    assert parameters.load_statements(tmp_path / "joint.json")["tolerance"] == doc["tolerance"]
    assert parameters.stated(tmp_path / "joint.json") == set(table) - left_out


def test_a_partial_file_is_completed_and_the_result_accepted(tmp_path, capsys):
    (tmp_path / "mine.json").write_text(json.dumps({"Kt": 0.05, "Ts": 1e-3, "tolerance": {"Kt": 0.2}}))
    code, _, err = run_cli(capsys, "params", "--params", tmp_path / "mine.json", "-o", tmp_path / "full.json")
    assert code == 0, err
    assert parameters.load(tmp_path / "full.json") == parameters.load(tmp_path / "mine.json")
    assert parameters.load_tolerances(tmp_path / "full.json")["Kt"] == 0.2
    assert json.loads((tmp_path / "full.json").read_text())["Ts"] == 1e-3  # kept: the file set it
    code, out, err = run_cli(capsys, "simulate", "--duration", "0.05", "--params", tmp_path / "full.json",
                             "-o", tmp_path / "rec.csv")
    assert code == 0, err


def test_without_output_it_prints_the_document(capsys):
    code, out, _ = run_cli(capsys, "params", "--defaults")
    assert code == 0 and json.loads(out)["Kt"] == parameters.defaults()["Kt"]


def test_a_unit_changed_in_the_documentation_is_refused(tmp_path, capsys):
    run_cli(capsys, "params", "--defaults", "-o", tmp_path / "joint.json")
    doc = json.loads((tmp_path / "joint.json").read_text())
    doc["documentation"]["Kt"]["unit"] = "mN.m/A"
    (tmp_path / "joint.json").write_text(json.dumps(doc))
    code, _, err = run_cli(capsys, "simulate", "--duration", "0.05", "--params", tmp_path / "joint.json",
                           "-o", tmp_path / "rec.csv")
    assert code == 2
    assert_one_line_error(err, "joint.json", "'Kt'", "'mN.m/A'", "'N.m/A'")


def test_the_defaults_file_lets_estimate_take_ts_and_jitter_from_a_4ms_recording(tmp_path, capsys):
    from hdjoint.fmu import experiments
    from hdjoint.io.recording import write_recording
    rec = experiments.run("paper", duration=1.0, sample_time=4e-3)
    write_recording(tmp_path / "slow.csv", rec)
    run_cli(capsys, "params", "--defaults", "-o", tmp_path / "joint.json")
    code, out, err = run_cli(capsys, "estimate", tmp_path / "slow.csv", "--params", tmp_path / "joint.json",
                             "--engine", "batch", "-o", tmp_path / "est.csv")
    assert code == 0, err
    assert "Ts = 0.004 s" in err and "reading-time jitter" in out
