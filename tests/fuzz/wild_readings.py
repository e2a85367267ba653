"""Wild readings fed to both estimators (the paper's UKF, tau_ukf, and the
joint-state filter, tau_hat): a recording of the paper experiment with, at a
random place, readings no sensor could produce -- a current of 1e30 or 1e200
(either sign), a current just beyond the gate's bound, a burst of NaN, an
encoder jumping 1000 counts for a burst of samples -- run through the batch
path (hdjoint._core) and JointTorqueEstimator as FMI 2.0 and FMI 3.0
Co-Simulation. NaN is the batch path's only: an FMU refuses a non-finite
input where it is set (fmi2SetReal, fmi3SetFloat64).

A finding is: a run that fails; a non-finite output; a wild sample the gate
let through (the batch path's status column counts each; an FMU warns once
for a run of them); a deviation that does not widen at each wild sample; and
an estimate not back on the clean run's within RECOVERY s of the last one. Used by
tests/fuzz/test_wild_readings.py (fixed seeds) and
benchmarks/fuzz_fmus.py --wild (a longer run)."""
from __future__ import annotations

import math
import random
from dataclasses import dataclass, field

import numpy as np

RECOVERY = 0.1  # s after the last wild sample: the estimates are the clean run's again
# How close "back" is: well inside the estimates' own spread on this recording
# (tau_ukf_std and tau_hat_std settle near 0.05 and 0.03 N.m).
TOLERANCE = {"tau_ukf": 0.05, "tau_hat": 0.05, "omega_m": 0.5}
OUTPUTS = ("tau_ukf", "tau_hat", "omega_m", "tau_ukf_std", "tau_hat_std")
ENGINES = ("batch", "fmi2", "fmi3")
KINDS = ("current", "current beyond the bound", "nan burst", "motor counts", "link counts")
INPUTS = ("i_m", "theta_m", "theta_l")
TWO_PI = 2.0 * math.pi


@dataclass
class Scenario:
    seed: int
    kind: str
    first: int            # the wild rows, first to last
    last: int
    column: str
    values: np.ndarray    # what the rows hold instead (row first + k: values[k])

    def describe(self) -> str:
        v = self.values[0]
        return f"seed {self.seed}: {self.kind}, {self.column} rows {self.first}-{self.last} (first {v!r})"


@dataclass
class Outcome:
    scenario: Scenario
    engine: str
    findings: list = field(default_factory=list)


def scenario(seed: int, recording, params: dict, engine: str) -> Scenario:
    """A random wild stretch for ENGINE (no NaN for an FMU), after the filters have settled."""
    rng = random.Random(seed)
    kinds = [k for k in KINDS if engine == "batch" or k != "nan burst"]
    kind = rng.choice(kinds)
    n = len(recording.time)
    first = rng.randrange(n // 4, n // 2)
    length = 1 if kind.startswith("current") and rng.random() < 0.6 else rng.randrange(1, 41)
    last = min(first + length - 1, n - 1)
    rows = slice(first, last + 1)
    if kind == "current":
        column = "i_m"
        values = np.full(last - first + 1, rng.choice([1e30, -1e30, 1e200, -1e200]))
    elif kind == "current beyond the bound":
        column = "i_m"
        values = np.full(last - first + 1, rng.choice([1, -1]) * 10.0 * params["i_peak"] * rng.uniform(1.01, 1e6))
    elif kind == "nan burst":
        column = rng.choice(INPUTS)
        values = np.full(last - first + 1, math.nan)
    else:
        column = "theta_m" if kind == "motor counts" else "theta_l"
        counts = params["motor_counts" if column == "theta_m" else "link_counts"]
        step = rng.choice([1000, -1000]) * TWO_PI / counts
        values = getattr(recording, column)[rows] + step
    return Scenario(seed, kind, first, last, column, np.asarray(values, float))


def inputs_of(recording, s: Scenario | None) -> np.ndarray:
    u = np.column_stack([getattr(recording, c) for c in INPUTS]).astype(float)
    if s is not None:
        u[s.first:s.last + 1, INPUTS.index(s.column)] = s.values
    return u


def run(engine: str, time, u, params: dict) -> tuple[dict, int]:
    """ENGINE over the rows: the outputs, and how many samples it counted as gated (the batch path) or how
    many times it said so (an FMU: once for a run of them)."""
    if engine == "batch":
        from hdjoint import _core
        out = _core.run_estimator(params, time, *(np.ascontiguousarray(u[:, k]) for k in range(3)), False)
        return {n: np.asarray(out[n]) for n in OUTPUTS}, int(np.sum(out["status"] == _core.STATUS_READING_GATED))
    if engine == "fmi2":
        from hdjoint.fmu.runner import run_estimator_fmu
        warnings: list[str] = []
        out = run_estimator_fmu(time, u[:, 0], u[:, 1], u[:, 2], params, outputs=OUTPUTS, warnings=warnings)
        return {n: np.asarray(out[n]) for n in OUTPUTS}, sum("no sensor could produce" in w for w in warnings)
    return _run_fmi3(time, u, params)


def _run_fmi3(time, u, params):
    import tempfile

    import fmpy
    from fmpy.fmi3 import FMU3Slave

    from hdjoint.fmu.shipped import fmu_path
    messages: list[str] = []
    with tempfile.TemporaryDirectory() as tmp:
        unzipdir = fmpy.extract(str(fmu_path("JointTorqueEstimator", 3)), tmp)
        md = fmpy.read_model_description(unzipdir)
        vr = {v.name: v.valueReference for v in md.modelVariables}
        slave = FMU3Slave(guid=md.guid, unzipDirectory=unzipdir, modelIdentifier=md.coSimulation.modelIdentifier,
                          instanceName="wild")
        slave.instantiate(logMessage=lambda env, status, category, message: messages.append(message.decode()))
        try:
            slave.enterInitializationMode(startTime=float(time[0]))
            names = [n for n in params if n in vr]
            slave.setFloat64([vr[n] for n in names], [float(params[n]) for n in names])
            slave.setFloat64([vr[n] for n in INPUTS], list(map(float, u[0])))
            slave.exitInitializationMode()
            steps = np.diff(np.append(time, time[-1] + params["Ts"]))
            vin, vout = [vr[n] for n in INPUTS], [vr[n] for n in OUTPUTS]
            out = np.empty((len(time), len(OUTPUTS)))
            for j in range(len(time)):
                slave.setFloat64(vin, list(map(float, u[j])))
                slave.doStep(float(time[j]), float(steps[j]))
                out[j] = slave.getFloat64(vout)
        finally:
            slave.freeInstance()
    return {n: out[:, k] for k, n in enumerate(OUTPUTS)}, sum("no sensor could produce" in m for m in messages)


def check(s: Scenario, engine: str, clean: dict, time, params: dict) -> Outcome:
    """Run ENGINE on the scenario's rows and compare with the clean run."""
    outcome = Outcome(s, engine)
    found = outcome.findings.append
    try:
        got, gated = run(engine, time, inputs_of(RECORDING[0], s), params)
    except Exception as e:  # a failed run is a finding, not the end of the campaign
        found(f"the run failed: {type(e).__name__}: {e}")
        return outcome
    wild = s.last - s.first + 1 if engine == "batch" else 1
    if gated != wild:
        found(f"{gated} gated sample(s) counted or said, {wild} expected")
    for name in OUTPUTS:
        if not np.all(np.isfinite(got[name])):
            found(f"{name} not finite at row {int(np.flatnonzero(~np.isfinite(got[name]))[0])}")
    for name in ("tau_ukf_std", "tau_hat_std"):
        std = got[name][s.first - 1:s.last + 1]
        if not np.all(np.diff(std) > 0):
            k = s.first + int(np.argmin(np.diff(std) > 0))
            found(f"{name} did not widen at wild row {k} ({got[name][k - 1]} -> {got[name][k]})")
    if not np.array_equal(got["tau_ukf"][:s.first], clean["tau_ukf"][:s.first]):
        found("the estimate changed before the first wild sample")
    back = s.last + int(math.ceil(RECOVERY / params["Ts"]))
    for name, tol in TOLERANCE.items():
        error = np.abs(got[name][back:] - clean[name][back:])
        if error.size and not np.max(error) <= tol:
            k = back + int(np.argmax(error))
            found(f"{name} not back {RECOVERY} s after the last wild sample: off by {np.max(error):.3g} at row {k} "
                  f"(time {time[k]:.4f} s)")
    return outcome


RECORDING: list = []  # the recording the scenarios are cut from (set by campaign)


def campaign(seeds, engines=ENGINES, duration: float = 1.0) -> list[Outcome]:
    """Every seed on every engine: their outcomes (findings empty when all is well)."""
    from hdjoint.fmu import experiments
    from hdjoint.io import parameters
    if not RECORDING:
        RECORDING.append(experiments.run("paper", duration=duration))
    recording = RECORDING[0]
    params = parameters.for_estimator(parameters.defaults())
    time = np.asarray(recording.time, float)
    outcomes = []
    for engine in engines:
        clean, gated = run(engine, time, inputs_of(recording, None), params)
        assert gated == 0, f"{engine}: the clean recording had {gated} gated sample(s)"
        for seed in seeds:
            outcomes.append(check(scenario(seed, recording, params, engine), engine, clean, time, params))
    return outcomes
