"""The second truth's cases: contract CSVs, the user's set, seeds, sensors."""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from hdjoint.io.recording import read_recording
from second_truth import cases
from second_truth.forms import FAMILIES, HELD_OUT
from second_truth.forms.encoder import EncoderFloor, EncoderRound

ROOT = Path(__file__).resolve().parents[2]
NAMES = set(re.findall(r"^HDJ_PARAMETER\((\w+),", (ROOT / "src/hdjoint/parameter_table.def").read_text(), re.M))
BUSY = {"motor_friction": "gms", "timing": "reading_jitter", "dropouts": "dropped_samples",
        "encoder": "encoder_round", "transmission_loss": "loss_factor"}


def _rows(path):
    return np.loadtxt(path, delimiter=",", skiprows=1)


@pytest.mark.parametrize("with_sensor", [True, False])
def test_csv_read_by_hdjoint(tmp_path, with_sensor):
    rec = cases.make_case(1002, tmp_path, forms=BUSY, duration=1.0, with_sensor=with_sensor)
    r = read_recording(tmp_path / rec["csv"])
    header = (tmp_path / rec["csv"]).read_text().splitlines()[0].split(",")
    assert header == ["time", "i_m", "theta_m", "theta_l"] + (["tau_sensor"] if with_sensor else [])
    data = _rows(tmp_path / rec["csv"])
    assert np.all(np.diff(data[:, 0]) > 0)
    assert len(data) == rec["rows"] and r is not None
    params = json.loads((tmp_path / rec["params"]).read_text())
    assert set(params) <= NAMES, set(params) - NAMES


def test_stamp_jitter_keeps_time_increasing(tmp_path):
    rec = cases.make_case(1004, tmp_path, forms={"timing": "stamp_jitter"}, duration=1.0)
    t = _rows(tmp_path / rec["csv"])[:, 0]
    dt = np.diff(t)
    assert np.all(dt > 0) and np.std(dt) > 1e-6  # jittery, yet increasing
    read_recording(tmp_path / rec["csv"])


def test_seed_determinism(tmp_path):
    a = cases.make_case(1003, tmp_path / "a", duration=0.5)
    b = cases.make_case(1003, tmp_path / "b", duration=0.5)
    c = cases.make_case(1005, tmp_path / "c", duration=0.5)
    ta, tb = (tmp_path / "a" / a["csv"]).read_bytes(), (tmp_path / "b" / b["csv"]).read_bytes()
    assert ta == tb and a["truth_params"] == b["truth_params"]
    assert (tmp_path / "c" / c["csv"]).read_bytes() != ta


def test_dropped_samples_make_gaps(tmp_path):
    rec = cases.make_case(1004, tmp_path, forms={"dropouts": "dropped_samples", "timing": None}, duration=2.0)
    t = _rows(tmp_path / rec["csv"])[:, 0]
    gaps = np.diff(t)
    assert rec["dropped"] > 0
    assert np.sum(gaps > 1.5e-3) > 0 and len(t) == 2001 - rec["dropped"]
    assert np.allclose(gaps[gaps < 1.5e-3], 1e-3)


def test_delay_shifts_the_current(tmp_path):
    """Same joint and noise, the planted time_delay only: the current is the plain one shifted."""
    kw = dict(forms={"timing": None, "dropouts": None}, excitation="chirp", duration=0.8)
    plain = cases.make_case(1013, tmp_path / "p", planted=[], **kw)
    late = cases.make_case(1013, tmp_path / "d", planted=["time_delay"], **kw)
    i0 = _rows(tmp_path / "p" / plain["csv"])[:, 1]
    i1 = _rows(tmp_path / "d" / late["csv"])[:, 1]
    d = late["planted"][0]["sizes"]["extra_delay"]
    lags = range(0, 8)
    err = [np.mean((i1[200 + m:] - i0[200:len(i0) - m]) ** 2) for m in lags]
    assert int(np.argmin(err)) == round(d / 1e-3)
    assert np.mean((i1 - i0) ** 2) > 4 * min(err)


def test_quantiser_floor_and_round_differ_by_half_a_count():
    rng = np.random.default_rng(0)
    ang = rng.uniform(-3, 3, 20000)
    zero = {k: 0.0 for k in ("e1_m", "e2_m", "e1_l", "e2_l")}
    fl = EncoderFloor(None, **zero).read(ang, "theta_l", 524288)
    ro = EncoderRound(None, **zero).read(ang, "theta_l", 524288)
    q = 2 * np.pi / 524288
    assert np.mean(ro - fl) == pytest.approx(q / 2, rel=0.02)
    assert np.all(fl <= ang + 1e-15) and np.max(np.abs(ro - ang)) <= q / 2 + 1e-15
    # the interpolation error moves the reading by a fraction of a signal period
    ie = EncoderRound(None, e1_l=0.01, e2_l=0.0, e1_m=0, e2_m=0, ph1=0.0, ph2=0.0).read(ang, "theta_l", 0)
    assert 0.5 * 0.01 * 2 * np.pi / 2048 < np.max(np.abs(ie - ang)) <= 0.01 * 2 * np.pi / 2048 * 1.0001


def test_user_set_leaves_out_what_is_planted(tmp_path):
    g = cases.make_case(1017, tmp_path, duration=0.3)
    assert g["planted"][0]["id"] == "gravity_load"
    assert g["user_params"]["mgl"] == 0.0 and g["truth_params"]["mgl"] > 2.5
    k = cases.make_case(1019, tmp_path, duration=0.3)
    assert k["user_params"]["Kf"] == 7000.0 and k["truth_params"]["Kf"] == 17500.0
    c = cases.make_case(1012, tmp_path, duration=0.3)
    assert c["control"] and c["user_params"]["Kf"] != c["truth_params"]["Kf"]  # nominal, not exact
    assert c["truth_params"]["Fs"] == 0.0 and c["truth_params"]["harmonics"] == []


def test_seed_split_and_held_out_families():
    assert not set(cases.TUNING_SEEDS) & set(cases.SEALED_SEEDS)
    assert HELD_OUT
    for s in cases.TUNING_SEEDS:
        f = cases.plan(s)["forms"]
        for fam in HELD_OUT:
            base = FAMILIES[fam]["baseline"]
            assert f[fam] == (base.name if base else None)
    used = {cases.plan(s)["forms"][fam] for s in cases.SEALED_SEEDS for fam in HELD_OUT}
    assert len(used) > 1  # the sealed seeds do draw the held-out forms
    planted = {e for s in cases.SEALED_SEEDS[:20] for e in cases.plan(s)["planted"]}
    assert planted == set(cases.EFFECT_ORDER)


def test_cli_writes_cases_and_manifest(tmp_path):
    assert cases.main(["--out", str(tmp_path), "--seeds", "tuning", "--limit", "2", "--duration", "0.3"]) == 0
    m = json.loads((tmp_path / "truth.json").read_text())
    assert m["seeds"] == "tuning" and [c["seed"] for c in m["cases"]] == [0, 1]
    for c in m["cases"]:
        assert (tmp_path / c["csv"]).exists() and (tmp_path / c["params"]).exists()
        assert c["split"] == "tuning" and c["held_out_used"] == []
    assert m["cases"][0]["control"] and m["cases"][1]["planted"][0]["id"] == cases.EFFECT_ORDER[0]


def test_ideal_current_sensor_reads_the_current_at_the_tick():
    """With no lag, delay, gain error or noise the recorded current is the joint's current at each tick."""
    from second_truth import nominal, recording
    from second_truth.controller import PDController
    from second_truth.excitations import reference
    from second_truth.forms.coulomb import Coulomb
    from second_truth.forms.current_sensor import LSB, CurrentSensor
    from second_truth.forms.tan_law import TanLaw
    from second_truth.joint import Joint

    truth, user = nominal.draw(np.random.default_rng(2))
    j = Joint(truth, [TanLaw(), Coulomb(None, omega_c=0.3)])
    Ts, D = 1e-3, 0.4
    r, rd, rdd = reference("dwell_reversals", D, Ts, np.random.default_rng(1))
    ideal = CurrentSensor(None, gain=1.0, offset=0.0, c3=0.0, tau_s=1e-9, delay=0.0, noise=0.0)
    rec = recording.record(j, PDController(dict(user, mgl=truth["mgl"]), r, rd, rdd, Ts), D, Ts, [ideal],
                           np.random.default_rng(0), {"motor_counts": 4096.0, "link_counts": 524288.0})
    i_tick = rec["sim"]["states"][:, 4]
    assert np.max(np.abs(rec["i_m"] - i_tick)) <= LSB / 2 + 1e-12
    late = CurrentSensor(None, gain=1.0, offset=0.0, c3=0.0, tau_s=1e-9, delay=0.0, noise=0.0, extra_delay=2e-3)
    assert np.allclose(late.probe_times(rec["ticks"])[::6], rec["ticks"] - 2e-3)
