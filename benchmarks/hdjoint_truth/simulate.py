"""Simulate the truth joint under a digital link-position controller and
log it as the contract's recording.

The plant has two inertias joined by the flexspline (eq. (2)-(8)): the
torsional mode (about 50 Hz for the default joint) and friction smoothed
over as little as 0.1 rad/s are stiff, so the default integrator is a
linearly implicit Euler (damping terms implicit, springs symplectic) at 5
substeps per sample; Heun's explicit scheme is the other form, drawn only
where the friction law is not stiff. The wave generator is loaded by the
transmitted torque tau_f/N of the previous substep (the physics, not the
paper's Kt*i_m approximation).

The controller reads the quantised motor encoder at each (jittered) sample
and applies its current from the next sample on (one sample of computation
delay), as a drive does."""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from hdjoint.io.recording import Recording
from hdjoint_truth import physics
from hdjoint_truth.excitations import external_load, reference
from hdjoint_truth.physics import Form
from hdjoint_truth.sensors import CurrentSensor, Encoder, sample_offsets


@dataclass
class Controller:
    """PID on the motor encoder (link reference times N) with the nominal model's feed-forward."""
    kp: float = 1.5            # A per motor rad
    ki: float = 4.0            # A per motor rad and second
    kd: float = 0.05           # A per motor rad/s
    speed_cutoff_hz: float = 120.0
    i_max: float = 5.0         # A


@dataclass
class Setup:
    """One recording: excitation, controller, sensors and seed."""
    excitation: str = "paper"
    duration: float = 30.0
    sample_time: float = 1e-3
    scale: float = 1.0                       # excitation amplitude factor
    controller: Controller = field(default_factory=Controller)
    motor_encoder: Encoder = field(default_factory=lambda: Encoder(4096.0))
    link_encoder: Encoder = field(default_factory=lambda: Encoder(524288.0))
    current_sensor: CurrentSensor = field(default_factory=CurrentSensor)
    torque_noise: float = 0.02               # N.m, std of the torque sensor
    with_torque_sensor: bool = True          # False: the recording has no tau_sensor column
    jitter: float = 0.0                      # s, samples taken up to this late
    stamp_actual_times: bool = False         # log the jittered instants (else the nominal ones)
    load: str = ""                           # external link torque (excitations.LOADS), unknown to the controller
    seed: int = 1


class _Plant:
    """The joint's state and one integration step; laws from physics.py."""

    def __init__(self, p: dict, form: Form, theta_l0: float):
        self.p, self.form = p, form
        self.N, self.Jm, self.Jl, self.Bm = p["N"], p["Jm"], p["Jl"], p["Bm"]
        self.Df, self.backlash = p.get("Df", 0.0), p.get("backlash", 0.0)
        self.hys = form.hysteresis
        self.bw = (p.get("bw_A", 0.0), p.get("bw_beta", 0.0), p.get("bw_gamma", 0.0))
        self.dahl = (p.get("dahl_H", 0.0), p.get("dahl_rate", 0.0))
        self.kinematic = physics.kinematic_terms(p, form)
        self.a0 = p["a0"]
        self.z_fric = 0.0
        self.z_hys = 0.0
        self.theta_l, self.omega_l, self.omega_m = theta_l0, 0.0, 0.0
        self.tau_f = p["mgl"] * math.sin(theta_l0)
        self.theta_m = self._static_motor_angle(theta_l0, self.tau_f)
        self.x_prev, self.x_rate = self.geometric(), 0.0

    def _static_motor_angle(self, theta_l: float, tau: float) -> float:
        """Motor angle that holds torque `tau` at rest (fixed point: theta_err depends on theta_m)."""
        p, cf, kf = self.p, self.p["Cf"], self.p["Kf"]
        x = math.atan(cf * tau) / (cf * kf) if cf > 0 else tau / kf
        x += math.copysign(0.5 * self.backlash, tau) if self.backlash else 0.0
        theta_m = self.N * theta_l
        for _ in range(8):
            theta_m = self.N * (theta_l + x + physics.wave_generator_torsion(p, tau / self.N)
                                + physics.kinematic_error(p, self.form, theta_m, theta_l))
        return theta_m

    def geometric(self) -> float:
        """Torsion less the kinematic error, before the wave generator's share:
        its rate is what the structural damping acts on. (The wave generator
        term is left out of the rate on purpose: it depends on the previous
        substep's torque, and differencing it closes an algebraic loop that
        Df/h amplifies beyond 1 per substep.)"""
        return (self.theta_m / self.N - self.theta_l
                - physics.kinematic_sum(self.a0, self.kinematic, self.theta_m, self.theta_l))

    def elastic(self) -> float:
        """Eq. (3)/(4)/(6): elastic torsion at the current state (wave generator loaded by the last tau_f)."""
        x = self.geometric() - physics.wave_generator_torsion(self.p, self.tau_f / self.N)
        if self.form.kinematic_torque:
            order, c = self.form.kinematic_torque
            x -= c * self.tau_f * math.cos(order * self.theta_m)
        return x

    def transmitted(self) -> float:
        """tau_f at the current state: eq. (8) on the elastic torsion past any lost motion, plus the
        hysteresis torque and structural damping of the elastic torsion rate (not the kinematic error's)."""
        x = self.elastic()
        if self.backlash:
            x = physics.dead_zone(x, self.backlash)
        return physics.flexspline_torque(self.p, x) + self.z_hys + self.Df * self.x_rate

    def _hysteresis(self, rate: float, h: float) -> None:
        """Implicit update of the hysteresis torque over h (both laws are stiff at speed)."""
        if self.hys == "bouc_wen":
            a, beta, gamma = self.bw
            z = self.z_hys
            self.z_hys = (z + h * a * rate) / (1.0 + h * (beta * abs(rate) + gamma * rate * math.copysign(1.0, z)))
        elif self.hys == "dahl_power":
            # dz/dt = r*rate*(1 - z/H*sign(rate))^2: a Dahl loop with a squared approach to saturation
            big, r = self.dahl
            z = self.z_hys
            s = 1.0 - z / big * math.copysign(1.0, rate)
            self.z_hys = z + h * r * rate * s * s / (1.0 + h * 2.0 * r * abs(rate) * s / big)

    def _motor_friction(self, t: float) -> tuple[float, float]:
        """(friction torque, its slope in omega_m) of the tanh law, Bm included."""
        f = self.form
        g = physics.friction_level(self.p, f, self.omega_m, t, self.theta_m, self.tau_f)
        th = math.tanh(self.omega_m / f.omega_fc)
        return g * th + self.Bm * self.omega_m, g / f.omega_fc * (1.0 - th * th) + self.Bm

    def step(self, h: float, current: float, t: float, tau_ext: float = 0.0) -> None:
        p, f = self.p, self.form
        x = self.geometric()
        self.x_rate, self.x_prev = (x - self.x_prev) / h, x
        tau_f = self.tau_f = self.transmitted()
        drive = physics.motor_torque_constant(p, f, t) * current + physics.cogging(p, self.theta_m)
        load = physics.link_load(p, f, self.theta_l, self.omega_l) - tau_ext
        fl = p.get("Fl", 0.0)
        c_l = p["Bl"] + (fl / f.link_omega_fc / math.cosh(self.omega_l / f.link_omega_fc) ** 2 if fl else 0.0)
        if f.integrator == "heun":
            self._heun(h, current, t, drive, tau_f, load, tau_ext)
            return
        if f.friction == "lugre":
            s0, s1 = f.lugre_sigma0, f.lugre_sigma1
            g = physics.friction_level(p, f, self.omega_m, t, self.theta_m, self.tau_f)
            zdot = self.omega_m - s0 * abs(self.omega_m) * self.z_fric / g
            # The friction's slope in omega_m over the step: the bristles take
            # the motion only while they are not yet deflected to their
            # sliding value (d(zdot)/d(omega) = 1 - s0*z*sign(omega)/g, 0 when
            # sliding). Taking s1 + s0*h while sliding, as before, weighed the
            # rotor by Jm + h*(s1 + s0*h): 2.25 Jm at the drawn s1 and h.
            yielding = max(0.0, 1.0 - s0 * self.z_fric * math.copysign(1.0, self.omega_m) / g)
            fric, c_m = s0 * self.z_fric + s1 * zdot + self.Bm * self.omega_m, (s1 + s0 * h) * yielding + self.Bm
        else:
            fric, c_m = self._motor_friction(t)
        wm = self.omega_m + h * (drive - fric - tau_f / self.N) / self.Jm / (1.0 + h * c_m / self.Jm)
        wl = self.omega_l + h * (tau_f - load) / self.Jl / (1.0 + h * c_l / self.Jl)
        if f.friction == "lugre":
            g = physics.friction_level(p, f, wm, t, self.theta_m, self.tau_f)
            self.z_fric = (self.z_fric + h * wm) / (1.0 + h * f.lugre_sigma0 * abs(wm) / g)
        self.omega_m, self.omega_l = wm, wl
        self.theta_m += h * wm
        self.theta_l += h * wl
        self._hysteresis(self.x_rate, h)

    def _heun(self, h, current, t, drive, tau_f, load, tau_ext):
        """Explicit second order (tanh friction only: no bristle state to keep stable)."""
        fric, _ = self._motor_friction(t)
        a_m = (drive - fric - tau_f / self.N) / self.Jm
        a_l = (tau_f - load) / self.Jl
        s0 = (self.theta_m, self.omega_m, self.theta_l, self.omega_l)
        self.theta_m, self.omega_m = s0[0] + h * s0[1], s0[1] + h * a_m
        self.theta_l, self.omega_l = s0[2] + h * s0[3], s0[3] + h * a_l
        tau_2 = self.transmitted()
        drive_2 = physics.motor_torque_constant(self.p, self.form, t + h) * current \
            + physics.cogging(self.p, self.theta_m)
        fric_2, _ = self._motor_friction(t + h)
        a_m2 = (drive_2 - fric_2 - tau_2 / self.N) / self.Jm
        a_l2 = (tau_2 - physics.link_load(self.p, self.form, self.theta_l, self.omega_l) + tau_ext) / self.Jl
        self.theta_m = s0[0] + 0.5 * h * (s0[1] + self.omega_m)
        self.theta_l = s0[2] + 0.5 * h * (s0[3] + self.omega_l)
        self.omega_m = s0[1] + 0.5 * h * (a_m + a_m2)
        self.omega_l = s0[3] + 0.5 * h * (a_l + a_l2)
        self._hysteresis(self.x_rate, h)


def check_form(form: Form) -> None:
    if form.friction not in ("tanh", "lugre"):
        raise ValueError(f"truth friction must be 'tanh' or 'lugre', not {form.friction!r}")
    if form.integrator not in ("semi_implicit", "heun"):
        raise ValueError(f"truth integrator must be 'semi_implicit' or 'heun', not {form.integrator!r}")
    if form.integrator == "heun" and (form.friction == "lugre" or form.omega_fc < 0.5):
        raise ValueError("Heun's explicit scheme is unstable with LuGre friction or omega_fc < 0.5 rad/s; "
                         "use the semi_implicit integrator")
    if form.hysteresis not in ("none", "bouc_wen", "dahl_power"):
        raise ValueError(f"truth hysteresis must be 'none', 'bouc_wen' or 'dahl_power', not {form.hysteresis!r}")
    if form.substeps < 1:
        raise ValueError(f"truth substeps must be >= 1, not {form.substeps}")


def simulate(truth: dict, form: Form, setup: Setup, nominal: dict) -> Recording:
    """Run the truth joint `truth` (parameter names of the contract plus the
    truth's own) under the controller, which knows only `nominal`."""
    check_form(form)
    rng = np.random.default_rng(setup.seed)
    ts, n_sub = setup.sample_time, form.substeps
    n = int(round(setup.duration / ts)) + 1
    t = np.arange(n) * ts
    th_ref, om_ref, al_ref = reference(setup.excitation, t, setup.scale)
    pushed = external_load(setup.load, t)
    N, Kt = nominal["N"], nominal["Kt"]
    feed_forward = ((nominal["Jm"] * N + nominal["Jl"] / N) * al_ref
                    + nominal["mgl"] * np.sin(th_ref) / N) / Kt
    h = ts / n_sub
    late = sample_offsets(n, min(setup.jitter, ts * (n_sub - 1) / n_sub), rng)
    at_substep = np.minimum(np.round(late / h).astype(int), n_sub - 1)

    plant = _Plant(truth, form, float(th_ref[0]))
    ctl = setup.controller
    alpha = 1.0 - math.exp(-2.0 * math.pi * ctl.speed_cutoff_hz * ts)
    theta_m, theta_l, tau, current, loop = (np.empty(n) for _ in range(5))
    read_m = setup.motor_encoder.read
    zero = float(read_m(np.array([plant.theta_m]))[0]) - N * th_ref[0]
    i_apply = float(feed_forward[0])
    previous, speed, integral = None, 0.0, 0.0
    for k in range(n):
        tk = t[k]
        for s in range(n_sub):
            if s == at_substep[k]:
                theta_m[k], theta_l[k] = plant.theta_m, plant.theta_l
                tau[k] = plant.transmitted()
                loop[k] = plant.z_hys
                current[k] = i_apply
            plant.step(h, i_apply, tk + s * h, float(pushed[k]))
        reading = float(read_m(np.array([theta_m[k]]))[0]) - zero
        speed = 0.0 if previous is None else speed + alpha * ((reading - previous) / ts - speed)
        previous = reading
        error = N * th_ref[k] - reading
        integral += error * ts
        i = feed_forward[k] + ctl.kp * error + ctl.ki * integral + ctl.kd * (N * om_ref[k] - speed)
        i_apply = min(max(i, -ctl.i_max), ctl.i_max)

    stamps = t + at_substep * h if setup.stamp_actual_times else t
    sensor = tau + rng.normal(0.0, setup.torque_noise, n) if setup.with_torque_sensor else None
    return Recording(time=stamps, i_m=setup.current_sensor.read(current, ts, rng),
                     theta_m=setup.motor_encoder.read(theta_m), theta_l=setup.link_encoder.read(theta_l),
                     tau_sensor=sensor, extra={"tau_joint": tau, "i_true": current, "hysteresis_torque": loop},
                     path=None)
