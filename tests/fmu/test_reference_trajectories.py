"""Both FMUs reproduce their committed reference trajectories
(tests/data/<FMU>_in.csv -> <FMU>_ref.csv) under fmpy's simulate_fmu.

Tolerances: torques 1e-6 N.m, speeds 1e-6 rad/s, torsion 1e-10 rad, angles one
encoder count (a quantised reading may flip at a count boundary when a
compiler rounds differently). On the build that wrote the files the
difference is round-off; a model change shows up as far more than this."""
from pathlib import Path

import numpy as np
import pytest
from fmpy import simulate_fmu

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.fmu.shipped import fmu_path

DATA = Path(__file__).resolve().parents[1] / "data"
TWO_PI = 2 * np.pi
DEFAULTS = parameters.defaults()

# The encoders' outputs may round to the neighbouring count; every other output
# by its unit (src/hdjoint/*_signals.def), so a new output needs no line here.
ONE_COUNT = {"theta_m": TWO_PI / DEFAULTS["motor_counts"] * 1.0001, "theta_l": TWO_PI / DEFAULTS["link_counts"] * 1.0001}
BY_UNIT = {"N.m": 1e-6, "rad/s": 1e-6, "rad": 1e-10}


def tolerance(fmu: str, column: str) -> float:
    if column in ONE_COUNT:
        return ONE_COUNT[column]
    unit = next(r["unit"] for r in _core.fmu_signals()[fmu] if r["name"] == column)
    return 1e-9 if column.endswith("_std") else BY_UNIT[unit]  # a standard deviation is smooth: tighter


def _read(path):
    return np.genfromtxt(path, delimiter=",", names=True)


@pytest.mark.parametrize("name", ["HarmonicDriveJoint", "JointTorqueEstimator"])
def test_fmu_reproduces_reference_trajectory(name):
    inputs = _read(DATA / f"{name}_in.csv")
    ref = _read(DATA / f"{name}_ref.csv")
    outputs = [c for c in ref.dtype.names if c != "time"]
    result = simulate_fmu(str(fmu_path(name)), stop_time=float(inputs["time"][-1]), step_size=1e-3,
                          output_interval=1e-3, input=inputs, output=outputs)
    assert len(result) == len(ref)
    np.testing.assert_allclose(result["time"], ref["time"], atol=1e-9)
    for column in outputs:
        error = np.max(np.abs(result[column] - ref[column]))
        assert error <= tolerance(name, column), f"{name}.{column} differs from its reference by {error:g}"


def test_reference_trajectories_exercise_the_model():
    """The references are not trivial: the joint moves and carries load."""
    joint = _read(DATA / "HarmonicDriveJoint_ref.csv")
    assert np.ptp(joint["theta_l"]) > 0.05 and np.ptp(joint["tau_joint"]) > 1.0
    est = _read(DATA / "JointTorqueEstimator_ref.csv")
    assert np.ptp(est["tau_ukf"]) > 0.2 and not np.allclose(est["tau_ukf"], est["tau_compliance"])
