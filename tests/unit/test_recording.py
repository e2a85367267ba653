"""Tests for hdjoint.io.recording (the contract's recording CSV format)."""

import os
import pickle

import numpy as np

from hdjoint.io.outputs import OutputError
import pytest

from hdjoint.io import recording
from hdjoint.io.recording import Recording, RecordingError, read_recording, write_csv, write_recording

HEADER = "time,i_m,theta_m,theta_l,tau_sensor\n"


def _make(tmp_path, text, name="data.csv"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _good_rows(n=5):
    return "".join(f"{k * 0.001},{0.1 * k},{0.2 * k},{0.002 * k},{k}\n"
                   for k in range(n))


def _error(path):
    with pytest.raises(RecordingError) as info:
        read_recording(path)
    return info.value


def _assert_names(err, path, line=None, column=None):
    """The message names the file, and the line/column when given."""
    msg = str(err)
    assert msg.startswith(f"{path}: "), msg
    if line is not None:
        assert f"line {line}" in msg, msg
        assert err.line == line
    if column is not None:
        assert f"column {column}" in msg, msg
        assert err.column == column


# ---------------------------------------------------------------- round trip


def _random_recording(n=200, seed=0, with_sensor=True):
    rng = np.random.default_rng(seed)
    return Recording(
        time=np.cumsum(rng.uniform(0.5e-3, 1.5e-3, n)),
        i_m=rng.standard_normal(n),
        theta_m=np.cumsum(rng.standard_normal(n)) * 1e3,
        theta_l=rng.standard_normal(n) * 1e-7,
        tau_sensor=rng.standard_normal(n) * 10 if with_sensor else None,
        extra={"temperature": 20 + rng.standard_normal(n)},
    )


@pytest.mark.parametrize("with_sensor", [True, False])
def test_round_trip_is_bit_exact(tmp_path, with_sensor):
    rec = _random_recording(with_sensor=with_sensor)
    path = tmp_path / "rec.csv"
    write_recording(path, rec)
    back = read_recording(path)
    assert back.path == str(path)
    assert len(back) == len(rec)
    for name, col in rec.columns().items():
        np.testing.assert_array_equal(back.columns()[name], col)
    assert (back.tau_sensor is None) == (not with_sensor)
    assert list(back.columns()) == list(rec.columns())


def test_round_trip_extreme_values(tmp_path):
    # Values whose '%g'-style formatting would lose bits.
    # The largest double goes in an extra column: a computed-with one refuses it (recording.MAX_MAGNITUDE).
    vals = np.array([0.1, 1 / 3, 1e-300, -5e-324, recording.MAX_MAGNITUDE, -0.0])
    path = tmp_path / "x.csv"
    write_csv(path, {"time": np.arange(6.0), "i_m": vals, "theta_m": vals,
                     "theta_l": vals, "extra": np.where(vals == recording.MAX_MAGNITUDE, 1.7976931348623157e308, vals)})
    back = read_recording(path)
    np.testing.assert_array_equal(back.i_m, vals)
    assert np.signbit(back.i_m[-1])
    assert back.extra["extra"][4] == 1.7976931348623157e308


def test_extra_columns_kept_numeric_and_text(tmp_path):
    text = ("time,i_m,label,theta_m,theta_l,temp\n"
            "0,1,start,2,3,nan\n"
            "1,1,run,2,3,21.5\n")
    rec = read_recording(_make(tmp_path, text))
    assert list(rec.extra) == ["label", "temp"]
    assert rec.extra["label"].tolist() == ["start", "run"]
    assert np.isnan(rec.extra["temp"][0]) and rec.extra["temp"][1] == 21.5
    assert rec.tau_sensor is None
    # ... and written back out again.
    out = tmp_path / "out.csv"
    write_recording(out, rec)
    again = read_recording(out)
    assert again.extra["label"].tolist() == ["start", "run"]


def test_tolerated_variations(tmp_path):
    # BOM, CRLF line ends, spaces around names/values, trailing blank lines.
    text = ("\ufefftime , i_m,theta_m,theta_l\r\n"
            "0, 1 ,2,3\r\n"
            "0.5,1,2,3\r\n\r\n")
    rec = read_recording(_make(tmp_path, text))
    np.testing.assert_array_equal(rec.time, [0, 0.5])


def test_quoted_file_uses_checked_loader(tmp_path):
    text = '"time","i_m","theta_m","theta_l"\n"0","1","2","3"\n1,1,2,3\n'
    rec = read_recording(_make(tmp_path, text))
    np.testing.assert_array_equal(rec.time, [0, 1])


def test_blank_lines_keep_line_numbers(tmp_path):
    # Line 4 is the bad one even though line 3 is blank.
    text = HEADER + "0,0,0,0,0\n\n0.1,0,x,0,0\n"
    err = _error(_make(tmp_path, text))
    _assert_names(err, tmp_path / "data.csv", line=4, column="theta_m")


# ---------------------------------------------------------------- errors


def test_missing_file(tmp_path):
    path = tmp_path / "nope.csv"
    err = _error(path)
    _assert_names(err, path)
    assert "not found" in str(err)


def test_directory_is_unreadable(tmp_path):
    err = _error(tmp_path)
    _assert_names(err, tmp_path)


def test_not_utf8(tmp_path):
    path = tmp_path / "bin.csv"
    path.write_bytes(b"time,i_m\n\xff\xfe\x00")
    _assert_names(_error(path), path)


@pytest.mark.parametrize("text", ["", "\n\n"])
def test_empty_file(tmp_path, text):
    path = _make(tmp_path, text)
    err = _error(path)
    _assert_names(err, path)
    assert "empty" in str(err)


def test_missing_required_column_is_named(tmp_path):
    path = _make(tmp_path, "time,i_m,theta_m,tau_sensor\n0,0,0,0\n1,0,0,0\n")
    err = _error(path)
    _assert_names(err, path, line=1)
    assert "theta_l" in str(err) and "missing" in str(err)


def test_duplicate_column(tmp_path):
    path = _make(tmp_path, "time,i_m,theta_m,theta_l,i_m\n0,0,0,0,0\n1,0,0,0,0\n")
    err = _error(path)
    _assert_names(err, path, line=1, column="i_m")
    assert "duplicate" in str(err)


def test_empty_column_name(tmp_path):
    path = _make(tmp_path, "time,i_m,theta_m,theta_l,\n0,0,0,0,0\n1,0,0,0,0\n")
    _assert_names(_error(path), path, line=1)


@pytest.mark.parametrize("bad_row", ["0.003,1,2", "0.003,1,2,3,4,5"])
def test_wrong_number_of_fields(tmp_path, bad_row):
    path = _make(tmp_path, HEADER + _good_rows(3) + bad_row + "\n" + _good_rows(1))
    err = _error(path)
    _assert_names(err, path, line=5)
    assert "expected 5 fields" in str(err)


def test_non_numeric_value(tmp_path):
    rows = _good_rows(20).splitlines()
    rows[15] = "0.015,1.5,30,abc,15"  # data row 16 = line 17
    path = _make(tmp_path, HEADER + "\n".join(rows) + "\n")
    err = _error(path)
    assert str(err) == f"{path}: line 17, column theta_l: not a number"
    assert err.path == str(path) and err.line == 17 and err.column == "theta_l"


@pytest.mark.parametrize("cell", ["", "1_0", "0x10", "1.2.3"])
def test_other_non_numbers(tmp_path, cell):
    path = _make(tmp_path, HEADER + f"0,{cell},0,0,0\n1,0,0,0,0\n")
    _assert_names(_error(path), path, line=2, column="i_m")


@pytest.mark.parametrize("cell", ["nan", "inf", "-inf", "NaN"])
def test_non_finite_value(tmp_path, cell):
    path = _make(tmp_path, HEADER + _good_rows(2) + f"0.01,0,0,0,{cell}\n")
    err = _error(path)
    _assert_names(err, path, line=4, column="tau_sensor")
    assert "finite" in str(err)


def test_earliest_bad_cell_is_reported(tmp_path):
    # theta_l goes bad on line 3, i_m only on line 4: line 3 wins.
    text = HEADER + "0,0,0,0,0\n0.1,0,0,bad,0\n0.2,bad,0,0,0\n"
    _assert_names(_error(_make(tmp_path, text)), tmp_path / "data.csv",
                  line=3, column="theta_l")


@pytest.mark.parametrize("t2", ["0.001", "0.0005"])
def test_time_not_increasing(tmp_path, t2):
    text = HEADER + "0,0,0,0,0\n0.001,0,0,0,0\n" + f"{t2},0,0,0,0\n"
    path = _make(tmp_path, text)
    err = _error(path)
    _assert_names(err, path, line=4, column="time")
    msg = str(err)
    assert "line 3" in msg and "strictly increasing" in msg
    assert t2 not in msg.replace(str(path), "")  # the file's contents are never quoted (issue 56)


@pytest.mark.parametrize("n", [0, 1])
def test_too_few_rows(tmp_path, n):
    path = _make(tmp_path, HEADER + _good_rows(n))
    err = _error(path)
    _assert_names(err, path)
    assert f"found {n}" in str(err)


def test_extra_column_nan_or_text_is_not_an_error(tmp_path):
    text = "time,i_m,theta_m,theta_l,note\n0,0,0,0,nan\n1,0,0,0,hello\n"
    rec = read_recording(_make(tmp_path, text))
    assert rec.extra["note"].tolist() == ["nan", "hello"]


def test_error_is_a_value_error_and_picklable(tmp_path):
    err = _error(_make(tmp_path, HEADER + "0,x,0,0,0\n1,0,0,0,0\n"))
    assert isinstance(err, ValueError)
    again = pickle.loads(pickle.dumps(err))
    assert str(again) == str(err) and again.line == err.line


# ---------------------------------------------------------------- writing


def test_write_csv_unequal_lengths(tmp_path):
    path = tmp_path / "out.csv"
    with pytest.raises(ValueError, match="'b' has 2 values but column 'a' has 3"):
        write_csv(path, {"a": [1, 2, 3], "b": [1, 2]})
    assert os.listdir(tmp_path) == []


class _Exploding:
    def __float__(self):
        raise RuntimeError("boom")


def test_write_failure_during_formatting_leaves_nothing(tmp_path):
    path = tmp_path / "out.csv"
    with pytest.raises(RuntimeError, match="boom"):
        write_csv(path, {"a": [1.0, 2.0], "b": np.array([1.0, _Exploding()],
                                                        dtype=object)})
    assert os.listdir(tmp_path) == []


def test_write_failure_mid_write_leaves_nothing_and_keeps_old_file(tmp_path, monkeypatch):
    path = tmp_path / "out.csv"
    path.write_text("old contents\n")

    def failing_replace(src, dst):
        raise OSError("disk full")

    monkeypatch.setattr(recording, "replace_into", failing_replace)  # the final move fails
    with pytest.raises(OutputError, match="disk full"):  # one line naming the path: exit 2 at the command line
        write_csv(path, {"a": np.arange(1000.0)})
    assert os.listdir(tmp_path) == ["out.csv"]
    assert path.read_text() == "old contents\n"


def test_write_replaces_existing_file(tmp_path):
    path = tmp_path / "out.csv"
    path.write_text("old\n")
    write_csv(path, {"a": [1.5, 2.5]})
    assert path.read_text() == "a\n1.5\n2.5\n"
    assert os.listdir(tmp_path) == ["out.csv"]


def test_write_recording_rejects_extra_named_like_contract_column(tmp_path):
    rec = _random_recording(n=3)
    rec.extra["i_m"] = np.zeros(3)
    with pytest.raises(ValueError, match="clash"):
        write_recording(tmp_path / "out.csv", rec)
    assert os.listdir(tmp_path) == []


# ---------------------------------------------------------------- Recording


def test_recording_helpers():
    t = np.arange(11) * 0.01
    rec = Recording(time=t, i_m=t, theta_m=t, theta_l=t, extra={"x": t * 2})
    assert len(rec) == 11
    assert rec.duration == pytest.approx(0.1)
    assert rec.median_step == pytest.approx(0.01)
    assert rec.sample_times_regular()
    part = rec.slice(2, 5)
    assert isinstance(part, Recording) and len(part) == 3
    np.testing.assert_array_equal(part.time, t[2:5])
    np.testing.assert_array_equal(part.extra["x"], t[2:5] * 2)
    part.time[0] = -1  # a copy: the original is untouched
    assert rec.time[2] == 0.02
    jittery = Recording(time=np.array([0, 1, 2, 3.5]), i_m=np.zeros(4),
                        theta_m=np.zeros(4), theta_l=np.zeros(4))
    assert not jittery.sample_times_regular(rtol=0.1)


def test_recording_rejects_mismatched_lengths():
    with pytest.raises(ValueError, match="theta_l"):
        Recording(time=[0, 1, 2], i_m=[0, 0, 0], theta_m=[0, 0, 0], theta_l=[0, 0])
