"""How real co-simulation masters call an FMU, for all three FMUs of the
joint-torque-feedback system (HarmonicDriveJoint, JointTorqueEstimator,
JointController): communication points and step sizes with floating-point
noise, step sizes that change during the run, a stop slightly short of or
past the stop time, inputs set before or after doStep, repeated fmi2Reset,
and many instances in one process.

Each FMU is driven open loop by smooth input signals (no feedback), so two
call patterns that mean the same thing must give the same outputs: exactly
where the FMU's arithmetic is the same, and within stated tolerances where
only the step partition differs.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from hdjoint.fmu.runner import FmuError, FmuInstance
from hdjoint.fmu.shipped import fmu_path

H = 1e-3
NOISY_H = 0.0009999999999976694   # a step size a master computed as (t1 - t0) in floating point

IO = {
    "HarmonicDriveJoint": (("i_m", "tau_ext"), ("theta_m", "theta_l", "tau_joint", "omega_m", "omega_link")),
    "JointTorqueEstimator": (("i_m", "theta_m", "theta_l"), ("tau_ukf", "tau_compliance", "omega_m", "dtheta_f")),
    "JointController": (("theta_m", "theta_l", "tau_fb"), ("i_m", "tau_ext", "theta_ref", "tau_d", "e_link")),
}
NAMES = tuple(IO)


def stimulus(name: str, t: float) -> list[float]:
    """Smooth inputs that make every output move (held over each step)."""
    s = math.sin(2 * math.pi * 0.5 * t)
    if name == "HarmonicDriveJoint":
        return [1.2 * s + 0.3, 0.5 * math.cos(2 * math.pi * 0.3 * t)]
    theta_l = 0.4 * s
    tau = 3.0 * s
    theta_m = 100.0 * theta_l + tau / 1.0e4 * 100.0
    if name == "JointTorqueEstimator":
        return [tau / (100 * 0.045), theta_m, theta_l]
    # The controller: a joint that follows its reference (0.5*(1 - cos)) closely.
    theta_l = 0.5 * (1 - math.cos(2 * math.pi * 0.25 * t)) + 0.002 * math.sin(2 * math.pi * 7 * t)
    return [100.0 * theta_l + 0.01 * s, theta_l, 0.9 * tau]


# The controller's load step falls inside the short runs here.
SETTINGS = {"JointController": {"dist_on": 0.1, "dist_off": 0.3}}


class Run:
    """One instance, driven through fmpy's FMU2Slave calls one by one."""

    def __init__(self, name: str, instance_name: str = "instance", stop_time: float | None = None,
                 parameters: dict[str, float] | None = None):
        self.name = name
        self.inputs, self.outputs = IO[name]
        self.fmu = FmuInstance(fmu_path(name), instance_name)
        self.parameters = {**SETTINGS.get(name, {}), **(parameters or {})}
        self.fmu.start(0.0, stop_time, self.parameters, dict(zip(self.inputs, stimulus(name, 0.0))))
        self.s = self.fmu.slave
        self.vin = self.fmu.value_references(self.inputs)
        self.vout = self.fmu.value_references(self.outputs)

    def steps(self, points, inputs_after_step: bool = False) -> np.ndarray:
        """Steps between consecutive communication points; inputs at each
        point are set before its doStep, or (as some masters do) right after
        the previous doStep. Returns the outputs after each step."""
        out = []
        if inputs_after_step:
            self.s.setReal(self.vin, stimulus(self.name, points[0]))
        for t0, t1 in zip(points[:-1], points[1:]):
            if not inputs_after_step:
                self.s.setReal(self.vin, stimulus(self.name, t0))
            self.fmu.call("fmi2DoStep", self.s.doStep, t0, t1 - t0)
            out.append(self.s.getReal(self.vout))
            if inputs_after_step:
                self.s.setReal(self.vin, stimulus(self.name, t1))
        return np.array(out)

    def close(self):
        self.fmu.close()


def clean_points(n: int) -> list[float]:
    return [k * H for k in range(n + 1)]


def reference(name: str, n: int = 400) -> np.ndarray:
    r = Run(name)
    try:
        return r.steps(clean_points(n))
    finally:
        r.close()


def assert_moves(out: np.ndarray):
    assert np.all(np.ptp(out, axis=0)[:3] > 0), "the comparison is empty: outputs do not move"


@pytest.fixture(scope="module")
def references():
    return {name: reference(name) for name in NAMES}


# ---- floating-point noise in communication points and step sizes ---------------------------

@pytest.mark.parametrize("name", NAMES)
def test_accumulated_noisy_steps_give_the_clean_trajectory(name, references):
    """Communication points accumulated as t += 0.0009999999999976694 (what
    a master that computes h = t1 - t0 passes): after 400 steps t is off
    by 1e-12 s. The samplers (estimator, controller) must take exactly one
    sample per step, so they match the clean run bit for bit or within
    1e-9 relative (the plant integrates h, 2e-12 relative shorter)."""
    r = Run(name)
    try:
        points = [0.0]
        for _ in range(400):
            points.append(points[-1] + NOISY_H)
        out = r.steps(points)
    finally:
        r.close()
    ref = references[name]
    assert_moves(ref)
    scale = np.maximum(np.abs(ref).max(axis=0), 1e-12)
    assert np.all(np.abs(out - ref) <= 1e-9 * scale), np.abs(out - ref).max(axis=0) / scale


@pytest.mark.parametrize("name", NAMES)
def test_points_that_are_k_times_h_with_round_off_give_the_clean_trajectory(name, references):
    """Points computed as k*0.001 carry round-off both ways (0.003 is
    0.0030000000000000001, 3*0.001 is 0.003000000000000000062...); the same
    points computed by summation differ from these by up to 1e-16 s each."""
    r = Run(name)
    try:
        points = [0.0]
        for k in range(400):
            points.append(points[-1] + H)   # 0.1 + 0.001 + ... drifts from k*H
        out = r.steps(points)
    finally:
        r.close()
    ref = references[name]
    scale = np.maximum(np.abs(ref).max(axis=0), 1e-12)
    assert np.all(np.abs(out - ref) <= 1e-9 * scale)


# ---- step sizes that change during the run -------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_changing_step_sizes_agree_on_the_common_grid(name):
    """Steps of 1, 0.5+0.5, 2, 0.3+0.7 and 5 ms in turn (every partition
    boundary on the 1 ms grid is hit), against 1 ms steps with the same
    held inputs. The samplers take their samples at k*Ts with the inputs of
    the step that holds them: equal to 1e-12 relative (the estimator's
    filters read them at the step's first sample only: its reference keeps
    the steps that hold samples). The plant integrates fixed substeps of
    max_step = 0.1 ms, and every step here is a multiple of it: the same
    substeps, so the same trajectory to round-off (1e-9 of each signal's
    range), its quantised encoders within one count (round-off can move a
    reading across a count boundary)."""
    pattern = [1.0, 0.5, 0.5, 2.0, 0.3, 0.7, 5.0]
    points, t_ms = [0.0], 0.0
    while t_ms < 400.0 - 1e-9:
        for d in pattern:
            if t_ms + d > 400.0 + 1e-9:
                break
            t_ms += d
            points.append(t_ms * 1e-3)
        else:
            continue
        break
    if abs(t_ms - 400.0) > 1e-9:
        points.append(0.4)
    # Both runs hold each input over a whole step of the variable run; the
    # reference steps every 1 ms with those same held values.
    def held(t):
        i = max(j for j, p in enumerate(points[:-1]) if p <= t + 1e-12)
        return stimulus(name, points[i])

    r = Run(name)
    try:
        out = {}
        for t0, t1 in zip(points[:-1], points[1:]):
            r.s.setReal(r.vin, stimulus(name, t0))
            r.fmu.call("fmi2DoStep", r.s.doStep, t0, t1 - t0)
            k = int(round(t1 / H))
            if abs(t1 / H - k) < 1e-9:
                out[k] = r.s.getReal(r.vout)
    finally:
        r.close()
    # The reference steps on the plant's substep grid (0.1 ms) for the
    # plant, on the sample grid (1 ms) for the controller: (start, step) pairs.
    fine = 10 if name == "HarmonicDriveJoint" else 1
    steps = [(k * H / fine, H / fine) for k in range(400 * fine)]
    if name == "JointTorqueEstimator":
        # The estimator's filters read the inputs at a step's first sample only and predict over
        # the others (a step of 2 or 5 ms is a gap to them): its reference keeps those steps
        # and merges each step that holds no sample (the 0.5 and 0.3 ms ones) into the one before.
        grid = lambda t: math.ceil(t / H - 1e-6)  # noqa: E731 - the first sample at or after t
        kept = [p for p, q in zip(points[:-1], points[1:]) if grid(p) < grid(q)] + [points[-1]]
        assert len(kept) < len(points) - 50  # steps without a sample were merged
        steps = [(t0, t1 - t0) for t0, t1 in zip(kept[:-1], kept[1:])]
    ref_run = Run(name, "reference")
    try:
        ref = {}
        for t0, h in steps:
            ref_run.s.setReal(ref_run.vin, held(t0))
            ref_run.fmu.call("fmi2DoStep", ref_run.s.doStep, t0, h)
            k = int(round((t0 + h) / H))
            if abs((t0 + h) / H - k) < 1e-9 and k in out:
                ref[k] = ref_run.s.getReal(ref_run.vout)
    finally:
        ref_run.close()
    out = {k: v for k, v in out.items() if k in ref}
    keys = sorted(out)
    got, want = np.array([out[k] for k in keys]), np.array([ref[k] for k in keys])
    assert len(keys) > 100
    assert_moves(want)
    rng = np.maximum(np.ptp(want, axis=0), 1e-12)
    tol = 1e-12 * rng
    if name == "HarmonicDriveJoint":
        tol = 1e-9 * rng
        tol[:2] = [2 * np.pi / 4096, 2 * np.pi / 524288]   # one count of each encoder
    assert np.all(np.abs(got - want) <= tol), np.abs(got - want).max(axis=0) / rng


# ---- stopping at, slightly short of and slightly past the stop time -----------------------------

@pytest.mark.parametrize("name", NAMES)
@pytest.mark.parametrize("last_point", [0.1 - 1e-13, 0.1, 0.1 + 1e-13, 0.1 + 2e-15])
def test_stop_time_reached_with_round_off_is_accepted(name, last_point):
    """stopTime = 0.1 s; the master's last communication point lands a hair
    short of or past it (accumulated round-off): every step is accepted."""
    r = Run(name, stop_time=0.1)
    try:
        points = clean_points(99) + [last_point]
        out = r.steps(points)
        assert np.all(np.isfinite(out))
        assert r.s.getRealStatus(2) == pytest.approx(last_point, abs=0)  # fmi2LastSuccessfulTime
    finally:
        r.close()


@pytest.mark.parametrize("name", NAMES)
def test_a_whole_step_past_the_stop_time_is_refused_with_a_message(name):
    """A step that ends a full step beyond stopTime is not round-off; the
    FMU says so (fmi2Error naming stopTime) instead of extrapolating."""
    r = Run(name, stop_time=0.1)
    try:
        r.steps(clean_points(100))
        with pytest.raises(FmuError, match="stopTime"):
            r.steps([0.1, 0.1 + H])
    finally:
        r.close()


@pytest.mark.parametrize("name", NAMES)
def test_a_master_that_stops_short_can_terminate_and_free(name):
    r = Run(name, stop_time=1.0)
    try:
        r.steps(clean_points(50))
    finally:
        r.close()  # terminate + free well before stopTime


# ---- inputs set before or after doStep -----------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_inputs_set_after_the_previous_step_equal_inputs_set_before_this_one(name, references):
    """Jacobi masters set the inputs for [t, t+h) right before doStep(t);
    others set them right after doStep(t-h) returned. Both are the same
    instant for the FMU: identical outputs, bit for bit."""
    r = Run(name)
    try:
        out = r.steps(clean_points(400), inputs_after_step=True)
    finally:
        r.close()
    assert np.array_equal(out, references[name])


@pytest.mark.parametrize("name", ["JointTorqueEstimator", "JointController"])
def test_inputs_set_in_initialization_mode_or_after_it_are_the_same(name):
    """The samplers' start inputs set during initialization mode, or only
    after exitInitializationMode before the first doStep: the same run from
    the first sample on. (Not the joint: it starts in static equilibrium
    under the tau_ext it is initialised with, by design.)"""
    def late(t):
        return stimulus(name, t + 0.05)   # non-zero from the start
    a = FmuInstance(fmu_path(name), "early-inputs")
    b = FmuInstance(fmu_path(name), "late-inputs")
    try:
        a.start(0.0, None, SETTINGS.get(name), dict(zip(IO[name][0], late(0.0))))
        b.start(0.0, None, SETTINGS.get(name), None)
        outs = []
        for inst in (a, b):
            vin, vout = inst.value_references(IO[name][0]), inst.value_references(IO[name][1])
            out = []
            for t0, t1 in zip(clean_points(200)[:-1], clean_points(200)[1:]):
                inst.slave.setReal(vin, late(t0))
                inst.slave.doStep(t0, t1 - t0)
                out.append(inst.slave.getReal(vout))
            outs.append(np.array(out))
    finally:
        a.close()
        b.close()
    assert_moves(outs[0])
    assert np.array_equal(outs[0], outs[1])


# ---- repeated fmi2Reset --------------------------------------------------------------------------

@pytest.mark.parametrize("name", NAMES)
def test_repeated_reset_gives_identical_runs(name, references):
    """Run, fmi2Reset, run again -- four times, resetting both after
    terminate and in the middle of a run: each run is the first one, bit
    for bit (nothing survives a reset)."""
    r = Run(name)
    try:
        points = clean_points(400)
        r.steps(points)                  # a whole first run
        for k in range(4):
            if k == 1:
                r.s.terminate()          # reset after terminate
            r.s.reset()
            r.fmu.start(0.0, None, r.parameters, dict(zip(r.inputs, stimulus(name, 0.0))))
            if k == 2:                   # reset in the middle of a run
                r.steps(points[:50])
                r.s.reset()
                r.fmu.start(0.0, None, r.parameters, dict(zip(r.inputs, stimulus(name, 0.0))))
            out = r.steps(points)
            assert np.array_equal(out, references[name]), f"run {k + 1} after reset differs"
    finally:
        r.close()


@pytest.mark.parametrize("name", NAMES)
def test_reset_restores_default_parameters(name):
    """A parameter changed before a reset is back to its default after it."""
    r = Run(name)
    try:
        var = {"HarmonicDriveJoint": "Jl", "JointTorqueEstimator": "ukf_q_tau", "JointController": "kp"}[name]
        vr = r.fmu.value_references([var])
        default = r.s.getReal(vr)[0]
        r.s.reset()
        r.s.setReal(vr, [default * 1.5])
        r.s.setupExperiment(startTime=0.0)
        r.s.enterInitializationMode()       # getReal is allowed from here on
        assert r.s.getReal(vr)[0] == default * 1.5
        r.s.reset()
        r.s.setupExperiment(startTime=0.0)
        r.s.enterInitializationMode()
        assert r.s.getReal(vr)[0] == default
    finally:
        r.close()


# ---- many instances in one process ------------------------------------------------------------------

def test_many_instances_of_all_three_fmus_interleaved_are_independent(references):
    """Thirty instances (ten of each FMU) stepped in lock-step, interleaved,
    half of them with a different parameter: each default instance gives the
    single-instance trajectory bit for bit, each changed one its own run."""
    changed = {"HarmonicDriveJoint": {"Jl": 0.3}, "JointTorqueEstimator": {"ukf_q_tau": 0.05},
               "JointController": {"kp": 3.0}}
    runs = []
    for name in NAMES:
        for i in range(10):
            runs.append(Run(name, f"{name}-{i}", parameters=changed[name] if i % 2 else None))
    try:
        points = clean_points(200)
        outs = [[] for _ in runs]
        for t0, t1 in zip(points[:-1], points[1:]):
            for r in runs:
                r.s.setReal(r.vin, stimulus(r.name, t0))
            for r in runs:
                r.fmu.call("fmi2DoStep", r.s.doStep, t0, t1 - t0)
            for r, out in zip(runs, outs):
                out.append(r.s.getReal(r.vout))
        for i, (r, out) in enumerate(zip(runs, outs)):
            out = np.array(out)
            ref = references[r.name][:200]
            if i % 2 == 0:
                assert np.array_equal(out, ref), f"{r.name} instance {i % 10} differs from a lone instance"
            else:
                assert not np.array_equal(out, ref), f"{r.name} instance {i % 10} ignored its parameter"
        # The changed ones agree among themselves.
        for name in NAMES:
            same = [np.array(o) for r, o, i in zip(runs, outs, range(len(runs))) if r.name == name and i % 2]
            assert all(np.array_equal(same[0], o) for o in same[1:])
    finally:
        for r in runs:
            r.close()
