"""The diagnosis on the real LARA8 recordings (tests/data/lara8, a copy of
../shared/data/lara8): what they can and cannot say, and the corrected
model checked on another recording of the same joint."""
import dataclasses
import sys
from pathlib import Path

import numpy as np
import pytest

from hdjoint.validation import validate

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "benchmarks"))
import lara8_table  # noqa: E402  (the LARA8 conventions: tooth ratio, current sign, nominal set)

DATA = Path(__file__).resolve().parents[1] / "data" / "lara8"


def test_validation_places_each_sets_encoder_zero_on_the_other_recording():
    """`hdjoint diagnose --validate` used the diagnosed recording's a0 on the
    other one; an encoder zeroed elsewhere (here 0.01 rad, after a power
    cycle) put its torsion past eq. (8)'s pole: every residual NaN, and
    error_figures failed on the empty array. The figures must not depend on
    where the encoders were zeroed."""
    rec = lara8_table.read_joint(DATA / "joint1_jog_linear_mass.csv")
    nominal = lara8_table.nominal_for(lara8_table.TOOTH_RATIO["joint1"])
    rezeroed = dataclasses.replace(rec, theta_l=rec.theta_l + 0.01)
    as_logged, moved = validate(rec, nominal, nominal, nominal), validate(rezeroed, nominal, nominal, nominal)
    for name, row in moved["channels"].items():
        for label, figures in row.items():
            assert np.isfinite(figures["rms"]), (name, label)
            assert figures["rms"] == pytest.approx(as_logged["channels"][name][label]["rms"], rel=1e-3)
