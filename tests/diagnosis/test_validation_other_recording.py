"""`hdjoint diagnose --validate`: the corrected model on another recording,
with what belongs to that recording placed on it (its current alignment) and
with a warning where it goes beyond the diagnosed recording's operating range."""
import sys
from pathlib import Path

import numpy as np

from hdjoint.diagnosis.model.torque_estimates import Prepared
from hdjoint.diagnosis.model.residual_channels import Evaluator, channels_for
from hdjoint.diagnosis.model.prepare import place_offset
from hdjoint.diagnosis.model.kinematics import kinematics
from hdjoint_truth.cases import CONTROL_CASES, draw, record
from hdjoint.diagnosis.verdict.validation import summary_line, validate

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import lara8_table  # noqa: E402  (the LARA8 conventions: tooth ratio, current sign, nominal set)

DATA = Path(__file__).resolve().parents[1] / "data" / "lara8"


def _prepared(rec):
    return Prepared(rec, kinematics(rec), rec.time - rec.time[0])


def test_a_held_current_is_realigned_on_the_other_recording():
    """The independent truth's drive holds each current over the following
    sample. The diagnosis calibrates that alignment on its own recording;
    --validate compared the other recording at the current's time stamps, so
    a model right in every parameter kept the N*Kt*Ts/2*di/dt of a chirp."""
    case = next(c for c in CONTROL_CASES if c.excitation == "chirp")
    joint = draw(case, 0, 6.0)
    rec = record(joint, 0)
    truth = dict(joint.nominal, **{k: v for k, v in joint.truth.items() if k in joint.nominal})
    entry = validate(rec, truth, truth, truth)
    step = float(np.median(np.diff(rec.time)))
    assert entry["current_alignment"]["corrected"] < -0.25 * step, entry["current_alignment"]

    prep = _prepared(rec)  # the same figure with the current at its time stamps
    evaluator = Evaluator(prep, channels_for(True))
    placed = place_offset(rec, truth, rec.tau_sensor)
    motor = next(c for c in evaluator.channels if c.name == "motor")
    unaligned = float(np.sqrt(np.nanmean(evaluator.residual(motor, placed)[prep.kin.valid] ** 2)))
    assert entry["channels"]["motor"]["corrected"]["rms"] < 0.95 * unaligned


def test_a_recording_beyond_the_fitted_speeds_is_flagged_as_extrapolated():
    """LARA8 joint3: the diagnosis of its first half (standing still) made its
    second half (moving) twelve times worse. That is the model extrapolated
    to speeds it was never fitted at, and --validate must say so; the same
    recording against itself must not."""
    rec = lara8_table.read_joint(DATA / "joint3_jog_linear_mass.csv")
    nominal = lara8_table.nominal_for(lara8_table.TOOTH_RATIO["joint3"])
    first, second = lara8_table.halves(rec)
    moved_on = validate(second, nominal, nominal, nominal, fitted_on=_prepared(first))
    speed = next(q for q in moved_on["extrapolation"] if q["quantity"] == "motor speed")
    assert speed["outside"] > 0.5 and "motor speed outside the fitted range" in speed["warning"]
    assert "extrapolated:" in summary_line(moved_on)

    itself = validate(first, nominal, nominal, nominal, fitted_on=_prepared(first))
    assert all("warning" not in q and q["outside"] < 0.02 for q in itself["extrapolation"]), itself["extrapolation"]
    assert "extrapolated" not in summary_line(itself)
