"""A fixed-seed FMI call-sequence fuzz run over the three FMUs, as FMI 2.0 and
FMI 3.0 Co-Simulation and (the joint) Model Exchange of both versions (the long run
is benchmarks/fuzz_fmus.py; the engine and its classes of finding are in
fmi_fuzzer.py). One run is shared by the tests below, each of which asserts
one class of finding is absent."""
from __future__ import annotations

import math
import os
import subprocess
import sys
import time

import pytest

from fmi_fuzzer import FMU_NAMES, ME_CALLS, Campaign, summarise
from hdjoint.fmu.shipped import fmu_path

# Every FMU of both versions, and the joint's Model Exchange interface of both.
TARGETS = ([fmu_path(n, fmi) for fmi in (2, 3) for n in FMU_NAMES]
           + [(fmu_path("HarmonicDriveJoint", fmi), True) for fmi in (2, 3)])
ME_TARGETS = ("HarmonicDriveJoint_me", "HarmonicDriveJoint_fmi3_me")

SEQUENCES_PER_FMU = 80
TIMEOUT = 1.5  # s of CPU time: a normal sequence takes ~50 ms
pytestmark = pytest.mark.slow  # one shared fuzz run: ~30 s


@pytest.fixture(scope="module")
def campaign(tmp_path_factory):
    return Campaign.load(TARGETS, tmp_path_factory.mktemp("fuzz"))


@pytest.fixture(scope="module")
def outcomes(campaign):
    assert len(campaign.fmus) == 8
    return {name: campaign.run(name, range(SEQUENCES_PER_FMU), TIMEOUT) for name in campaign.fmus}


def findings(outcomes, category):
    return [(name, o.seed, f[1], o.ops[f[1]] if f[1] >= 0 else None, f[2])
            for name, runs in outcomes.items() for o in runs for f in o.findings if f[0] == category]


def test_the_run_covers_every_fmu_with_many_calls(outcomes):
    for name, runs in outcomes.items():
        summary = summarise(runs)
        assert summary["sequences"] == SEQUENCES_PER_FMU
        assert summary["calls"] > 20 * SEQUENCES_PER_FMU, (name, summary)
        kinds = {op[0] for o in runs for op in o.ops}
        assert {"step", "set", "get", "deserialize", "setstate", "reset", "free", "terminate"} <= kinds
        assert set(ME_CALLS) <= kinds or name not in ME_TARGETS, (name, kinds)


def test_no_fmu_crashes(outcomes):
    assert findings(outcomes, "crash") == []


def test_no_fmu_hangs(outcomes):
    assert findings(outcomes, "hang") == []


def test_no_illegal_call_is_accepted(outcomes):
    assert findings(outcomes, "illegal call accepted") == []


def test_no_corrupted_state_is_accepted(outcomes):
    assert findings(outcomes, "corrupted state accepted") == []


def test_no_non_finite_output_after_ok(outcomes):
    assert findings(outcomes, "non-finite output") == []


# ---- the harness itself: what it must classify


def test_a_child_killed_by_a_signal_is_a_crash(campaign, capfd):
    capfd.readouterr()
    outcome = campaign.replay("JointController", [["instantiate"], ["_selftest", "crash", 0]], TIMEOUT)
    assert [(f[0], f[1]) for f in outcome.findings] == [("crash", 1)]
    assert "SIGSEGV" in outcome.findings[0][2]
    # The crash made on purpose: its trace is captured in the outcome, not printed on the test log.
    assert "Fatal Python error: Segmentation fault" in outcome.trace
    assert "Fatal Python error" not in capfd.readouterr().err


def test_an_unbounded_loop_is_a_hang_once_it_has_used_its_cpu_budget(campaign):
    outcome = campaign.replay("JointController", [["instantiate"], ["_selftest", "spin", math.inf]], 0.3)
    assert [(f[0], f[1]) for f in outcome.findings] == [("hang", 1)]
    assert "0.3 s of CPU time" in outcome.findings[0][2]
    assert outcome.seconds < 5


def test_a_child_blocked_without_computing_is_a_hang_at_the_wall_clock_backstop(campaign):
    outcome = campaign.replay("JointController", [["instantiate"], ["_selftest", "sleep", 30]], 0.5, backstop=1.0)
    assert [(f[0], f[1]) for f in outcome.findings] == [("hang", 1)]
    assert "wall-clock backstop" in outcome.findings[0][2]
    assert outcome.seconds < 5


def test_a_slow_but_bounded_call_on_a_loaded_core_is_no_hang(campaign):
    # Three busy processes share one core with the child, which needs 0.3 s of
    # CPU time within a 0.5 s budget: its wall time is well over the budget
    # (a hang to a wall-clock rule), its CPU time is not.
    core = min(os.sched_getaffinity(0))
    hogs = [subprocess.Popen([sys.executable, "-c", f"import os; os.sched_setaffinity(0, {{{core}}})\nwhile True: pass"])
            for _ in range(3)]
    try:
        time.sleep(0.2)  # the hogs are running
        outcome = campaign.replay("JointController", [["instantiate"], ["_selftest", "pin", core],
                                                      ["_selftest", "spin", 0.3], ["get", ["tau_d"]]], 0.5)
    finally:
        for hog in hogs:
            hog.kill()
            hog.wait()
    assert outcome.seconds > 0.5, "the core was not loaded: the test shows nothing"
    assert outcome.findings == [] and outcome.calls == 4


def test_a_legal_run_has_no_finding(campaign):
    ops = [["instantiate"], ["setup", 0.0, 1.0], ["enter"], ["exit"]]
    ops += [["step", k * 1e-3, 1e-3] for k in range(20)] + [["get", ["tau_d", "i_m"]], ["terminate"]]
    outcome = campaign.replay("JointController", ops, TIMEOUT)
    assert outcome.findings == [] and outcome.calls == len(ops)


LEGAL_ME_RUN = [["instantiate"], ["setup", 0.0, 1.0], ["enter"], ["exit"], ["update"], ["enterct"], ["getx", 0],
                ["settime", 1e-3], ["setx", 1e-6, None, 0.0, 0], ["getdx", 0], ["getz", 0], ["completed"],
                ["get", ["tau_joint", "theta_m"]], ["enterevent"], ["update"], ["enterct"], ["terminate"]]


@pytest.mark.parametrize("name", ME_TARGETS)
def test_a_legal_model_exchange_run_has_no_finding(campaign, name):
    outcome = campaign.replay(name, LEGAL_ME_RUN, TIMEOUT)
    assert outcome.findings == [] and outcome.calls == len(LEGAL_ME_RUN)


def test_an_accepted_illegal_model_exchange_call_is_found(campaign):
    # The harness's table decides legality: with getdx declared illegal, the
    # FMU's (correct) acceptance of it must show as a finding.
    fmu = campaign.fmus["HarmonicDriveJoint_fmi3_me"]
    table = fmu.allowed
    fmu.allowed = {**table, "getdx": set()}
    try:
        outcome = campaign.replay(fmu.name, LEGAL_ME_RUN, TIMEOUT)
    finally:
        fmu.allowed = table
    assert [(f[0], LEGAL_ME_RUN[f[1]][0]) for f in outcome.findings] == [("illegal call accepted", "getdx")]
