"""Minimised reproducers of what the fuzzer (and the audit of issue 12)
found, replayed by the fuzzer's engine: each must show no finding."""
from __future__ import annotations

import pytest

from fmi_fuzzer import FMU_NAMES, Campaign
from hdjoint.fmu.shipped import fmu_path

pytestmark = pytest.mark.slow  # the hang reproducers wait out their budget
START = [["instantiate"], ["setup", 0.0, None], ["enter"], ["exit"]]

REPRODUCERS = {
    # A step of 1e6 s at a communication point 0.47 s off: accepted (the
    # tolerance grows with the step), then the per-sample loop never ends.
    "estimator: huge step, wrong communication point": (
        "JointTorqueEstimator", [["instantiate"], ["enter"], ["exit"], ["step", -0.4666356861196215, 1e6]]),
    "controller: huge step": ("JointController", START + [["step", 0.0, 1e300]]),
    "joint: a step of 215 s takes millions of substeps": ("HarmonicDriveJoint", START + [["step", 0.0, 215.0]]),
    "terminate in the error state": (
        "JointController", [["instantiate"], ["exit"], ["terminate"]]),
    "status query in the error state": (
        "HarmonicDriveJoint", [["instantiate"], ["exit"], ["status", "plain"]]),
    "a state of another FMU deserialises": (
        "JointTorqueEstimator", [["instantiate"], ["deserialize", 0, ["foreign", "HarmonicDriveJoint"], 0]]),
    "a state-machine field edited to an invalid value": (
        "JointController", START + [["getstate", 0], ["serialize", 0, 0], ["deserialize", 0, ["state", 0, 64.0], 1]]),
    # Found by the long fuzz run (benchmarks/fuzz_fmus.py): a
    # state-machine field edited to another valid state deserialised (error
    # or step complete edited to "instantiated"); the state's CRC-32 seal refuses it.
    "controller: error state edited to instantiated (seed 121)": (
        "JointController", [["instantiate"], ["get", ["i_m", "tau_ext", "theta_ref", "tau_d", "e_link"]],
                            ["getstate", 0], ["serialize", 0, 2], ["deserialize", 2, ["state", 0, 1.0], 0]]),
    "estimator: step complete edited to instantiated (seed 140)": (
        "JointTorqueEstimator", START + [["step", 0.0, 1e-3], ["getstate", 0], ["serialize", 0, 0],
                                         ["deserialize", 0, ["state", 0, 1.0], 1], ["setstate", 1]]),
    "a NaN field in a serialised state": (
        "JointTorqueEstimator", START + [["getstate", 0], ["serialize", 0, 0],
                                         ["deserialize", 0, ["nonfinite", 9, float("nan")], 1]]),
    "encoder counts too small to quantise": (
        "HarmonicDriveJoint", [["instantiate"], ["setup", 0.0, None], ["set", "motor_counts", 5e-324], ["enter"],
                               ["exit"], ["step", 0.0, 1e-3], ["get", ["theta_m", "theta_l", "tau_joint"]]]),
}


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    return Campaign.load([fmu_path(n) for n in FMU_NAMES], tmp_path_factory.mktemp("fuzz"))


@pytest.mark.parametrize("case", list(REPRODUCERS))
def test_reproducer_shows_no_finding(campaign, case):
    fmu, ops = REPRODUCERS[case]
    outcome = campaign.replay(fmu, ops, timeout=1.5)
    assert outcome.findings == []
    assert outcome.calls == len(ops)
