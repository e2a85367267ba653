"""Built-in experiments: the joint (HarmonicDriveJoint.fmu, through fmpy)
under a position controller, recorded in the contract's format.

The joint that is simulated is not the nominal one: real joints differ from
their catalogue model by a few percent in every parameter and by more in the
kinematic error. `TRUE_JOINT_DEVIATIONS` says how the simulated joint differs
from the defaults that the estimator assumes, so the reported errors are the
systematic ones a user meets, not only noise.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.fmu.runner import FmuInstance
from hdjoint.fmu.shipped import fmu_path
from hdjoint.io.recording import Recording

# How the simulated ("true") joint differs from the nominal parameter set.
TRUE_JOINT_DEVIATIONS = {
    "Kt": 1.03,      # torque constant 3 % above its data-sheet value
    "Kf": 0.95,      # flexspline 5 % softer
    "Cf": 1.10,
    "Fc": 1.30,      # more friction than assumed
    "al1": 1.35,     # kinematic error differs from the nominal fit
    "bl1": 0.60,
    "aw1": 1.25,
    "bw1": 1.20,
    "aw2": 0.80,
    "bw2": 1.50,
}
# The joint FMU's wave generator carries the transmitted torque tau/N; the
# estimator's default is the paper's tau_w = Kt*i_m. (Flexspline damping Df
# stays at 0 so the published figures keep their meaning; the plant applies
# it to the elastic torsion rate only, without the kinematic error's.)
TRUE_JOINT_EXTRA: dict[str, float] = {}


def true_joint_parameters(nominal: dict[str, float] | None = None) -> dict[str, float]:
    p = dict(nominal or parameters.defaults())
    for name, factor in TRUE_JOINT_DEVIATIONS.items():
        p[name] *= factor
    p.update(TRUE_JOINT_EXTRA)
    return p


@dataclass
class Sensors:
    """Measurement noise added to what the recording holds (encoders are quantised by the FMU)."""
    current_noise: float = 0.01   # A, std of the current measurement
    torque_noise: float = 0.02    # N.m, std of the torque sensor
    seed: int = 1


@dataclass
class Controller:
    """Link position PD on the motor encoder with nominal gravity feed-forward
    (the C++ JointController's law, without the torque loop)."""
    kp: float = 2.0        # A per motor rad
    kd: float = 0.06       # A per motor rad/s
    speed_filter_hz: float = 150.0
    i_max: float = 4.0     # A

    def native(self, sample_time: float, N: float, Kt: float, mgl: float) -> dict[str, float]:
        """The C++ controller's parameters (controller_table.def) for these gains."""
        return {"Ts": sample_time, "kp": self.kp, "kd": self.kd, "speed_filter": 2.0 * math.pi * self.speed_filter_hz,
                "i_max": self.i_max, "N": N, "Kt": Kt, "mgl": mgl, "jtf": 0.0}


@dataclass
class Experiment:
    name: str
    duration: float
    reference: Callable[[np.ndarray], tuple[np.ndarray, np.ndarray]]  # t -> (theta_l_ref, omega_l_ref)
    description: str
    tau_ext: Callable[[np.ndarray], np.ndarray] = field(default=lambda t: np.zeros_like(t))


def _paper_reference(t):
    # 58 s sinusoid whose amplitude grows, so the gravity torque grows
    # gradually to about 5 N.m (the paper's test torque).
    amplitude = 0.05 + 1.15 * t / 58.0
    w = 2.0 * math.pi * 0.25
    theta = amplitude * np.sin(w * t)
    omega = amplitude * w * np.cos(w * t) + (1.15 / 58.0) * np.sin(w * t)
    return theta, omega


def _repeated_paper_reference(t):
    # The paper's run over and over (a long bench test): each 58 s cycle
    # starts and ends at zero angle, so the reference stays continuous.
    return _paper_reference(np.mod(t, 58.0))


def _multisine_reference(t):
    # Five incommensurate sines, 0.13-2.9 Hz: broadband torque and speed
    # reversals at many levels.
    theta = np.zeros_like(t)
    omega = np.zeros_like(t)
    for amplitude, hz, phase in ((0.6, 0.13, 0.0), (0.25, 0.41, 1.0), (0.08, 1.07, 2.0), (0.03, 1.9, 0.5),
                                 (0.012, 2.9, 2.5)):
        w = 2.0 * math.pi * hz
        theta += amplitude * np.sin(w * t + phase)
        omega += amplitude * w * np.cos(w * t + phase)
    return theta - 0.6 * math.sin(0.0) - 0.25 * math.sin(1.0) - 0.08 * math.sin(2.0) - 0.03 * math.sin(0.5) \
        - 0.012 * math.sin(2.5), omega


def _smooth_ramp(x):
    """0 -> 1 over x in [0, 1] with zero slope at both ends (and its derivative)."""
    x = np.clip(x, 0.0, 1.0)
    return x * x * (3.0 - 2.0 * x), 6.0 * x * (1.0 - x)


def _sweep_reference(t):
    # Slow moves between link angles with dwells: 2 s move, 2 s dwell.
    targets = np.array([0.0, 0.8, -0.5, 1.1, 0.2, -0.9, 0.6, 0.0])
    period, move = 4.0, 2.0
    k = np.minimum((t // period).astype(int), len(targets) - 2)
    ramp, slope = _smooth_ramp((t - k * period) / move)
    theta = targets[k] + (targets[k + 1] - targets[k]) * ramp
    omega = (targets[k + 1] - targets[k]) * slope / move
    return theta, omega


def _chirp_reference(t):
    # Linear chirp 0.1 -> 4 Hz over 30 s, amplitude falling as the frequency
    # rises (constant acceleration level), faded in over 1 s.
    f0, f1, T = 0.1, 4.0, 30.0
    phase = 2.0 * math.pi * (f0 * t + 0.5 * (f1 - f0) / T * t * t)
    freq = f0 + (f1 - f0) * t / T
    amplitude = 0.5 * (f0 + 0.2) / (freq + 0.2)
    fade, dfade = _smooth_ramp(t / 1.0)
    theta = fade * amplitude * np.sin(phase)
    # d/dt of amplitude*sin(phase), amplitude' small but kept.
    damp = -0.5 * (f0 + 0.2) * (f1 - f0) / T / (freq + 0.2) ** 2
    omega = fade * (amplitude * 2.0 * math.pi * freq * np.cos(phase) + damp * np.sin(phase)) \
        + dfade * amplitude * np.sin(phase)
    return theta, omega


EXPERIMENTS = {
    "paper": Experiment(
        "paper", 58.0, _paper_reference,
        "Yu et al. 2018, section IV: 58 s sinusoid with gradually growing torque, 1 kHz, "
        "1024-line motor encoder in quadrature, 19-bit link encoder, sensor noise"),
    "paper_repeated": Experiment(
        "paper_repeated", 3600.0, _repeated_paper_reference,
        "the paper experiment repeated for an hour (58 s cycles): a long recording for the diagnosis' speed"),
    "multisine": Experiment(
        "multisine", 30.0, _multisine_reference,
        "30 s multisine (five incommensurate sines, 0.13-2.9 Hz) on the link angle"),
    "sweep": Experiment(
        "sweep", 30.0, _sweep_reference,
        "30 s of slow point-to-point moves (2 s) with 2 s dwells between them"),
    "chirp": Experiment(
        "chirp", 30.0, _chirp_reference,
        "30 s linear chirp 0.1 -> 4 Hz, amplitude falling with frequency"),
}


def payload_steps(t, levels=(0.0, 1.5, -1.0, 2.5, 0.5), hold=6.0, rise=0.05):
    """External link torque: a payload changing every `hold` seconds (steps with a short rise)."""
    t = np.asarray(t, float)
    k = np.minimum((t // hold).astype(int), len(levels) - 1)
    previous = np.array(levels)[np.maximum(k - 1, 0)]
    ramp, _ = _smooth_ramp((t - k * hold) / rise)
    return previous + (np.array(levels)[k] - previous) * ramp


def contact_pushes(t, every=3.7, width=0.8, peak=3.0):
    """External link torque: contact pushes (raised-cosine pulses) of alternating sign."""
    t = np.asarray(t, float)
    k = np.floor(t / every)
    x = (t - k * every) / width
    pulse = np.where(x < 1.0, 0.5 * (1.0 - np.cos(2.0 * math.pi * np.clip(x, 0.0, 1.0))), 0.0)
    return peak * pulse * np.where(k % 2 == 0, 1.0, -0.6)


def run(name: str = "paper", joint: dict[str, float] | None = None, nominal: dict[str, float] | None = None,
        sample_time: float = 1e-3, sensors: Sensors | None = None, controller: Controller | None = None,
        duration: float | None = None, tau_ext: Callable[[np.ndarray], np.ndarray] | None = None) -> Recording:
    """Simulate a built-in experiment; returns the recording.

    `joint` is the simulated joint's parameter set (default: the nominal set
    with TRUE_JOINT_DEVIATIONS); `nominal` what the controller assumes;
    `tau_ext` an external link torque profile t -> N.m (default: the
    experiment's, none), unknown to the controller.
    The recording holds the contract columns plus `tau_joint` (the true
    transmitted torque) and `i_cmd` (the current actually applied).
    """
    if name not in EXPERIMENTS:
        raise ValueError(f"unknown experiment '{name}'; known: {', '.join(EXPERIMENTS)}")
    exp = EXPERIMENTS[name]
    nominal = nominal or parameters.defaults()
    joint = joint or true_joint_parameters(nominal)
    sensors = sensors or Sensors()
    ctl = controller or Controller()
    n = int(round((duration or exp.duration) / sample_time)) + 1
    t = np.arange(n) * sample_time
    theta_ref, omega_ref = exp.reference(t)
    tau_ext = (tau_ext or exp.tau_ext)(t)
    N, Kt, mgl = nominal["N"], nominal["Kt"], joint_gravity_guess(nominal)

    out = np.empty((n, 3))
    i_cmd = np.empty(n)
    # The C++ controller (JointController.fmu's law) on this experiment's reference.
    law = _core.JointController(ctl.native(sample_time, N, Kt, mgl))
    with FmuInstance(fmu_path("HarmonicDriveJoint"), "joint") as plant:
        plant.start(0.0, None, parameters.for_plant(joint), {"i_m": 0.0, "tau_ext": float(tau_ext[0])})
        stepper = plant.stepper(("i_m", "tau_ext"), ("theta_m", "theta_l", "tau_joint"))
        out[0] = plant.get(("theta_m", "theta_l", "tau_joint"))
        theta_m0 = out[0, 0]  # the controller counts the motor angle from its start
        for j in range(n):
            i_cmd[j] = law.command(out[j, 0] - theta_m0, theta_ref[j], omega_ref[j])
            if j + 1 < n:
                out[j + 1] = stepper.step(t[j], sample_time, (i_cmd[j], tau_ext[j]))

    rng = np.random.default_rng(sensors.seed)
    return Recording(
        time=t, i_m=i_cmd + rng.normal(0.0, sensors.current_noise, n), theta_m=out[:, 0], theta_l=out[:, 1],
        tau_sensor=out[:, 2] + rng.normal(0.0, sensors.torque_noise, n),
        extra={"tau_joint": out[:, 2].copy(), "i_cmd": i_cmd}, path=None)


def joint_gravity_guess(nominal: dict[str, float]) -> float:
    """The gravity torque amplitude the controller feeds forward (its nominal mgl)."""
    return nominal.get("mgl", parameters.table()["mgl"].default)
