"""Independent estimates of the same joint torque, one per part of the model.

  tau_T  transmission: the encoders through eq. (3)-(8) (the C++ compliance
         model, with every beyond-paper term the parameter set switches on),
         plus the flexspline's structural damping Df (against a sensor, the
         hysteresis loop's slow drive is tau_L's torsion: hysteresis_torque)
  tau_M  motor: the current through eq. (2), N*(Kt*i + cogging - Jm*alpha_m
         - friction(omega_m, t)), friction and cogging by the C++ laws, each
         through the same smoothing filter as the encoders' acceleration
  tau_L  link: the link's motion, Jl*alpha_l + Bl*omega_l + mgl*sin(theta_l)
         + link friction (no external torque assumed), the C++ link equation
  tau_S  the torque sensor, when the recording has one

The differences between them are the residual channels the diagnosis
localises mismatches in: an effect lives in one part of the model.
"""
from __future__ import annotations

import functools
from collections import OrderedDict
from dataclasses import dataclass, field

import numpy as np

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.io.recording import Recording
from hdjoint.diagnosis.effects import friction_law_parameters, part_parameters
from hdjoint.diagnosis.effects.kinematic_error import EFFECT as KINEMATIC_ERROR
from hdjoint.diagnosis.effects.kinematic_error import KINEMATIC_EQ7
from hdjoint.diagnosis.forked import threads_here
from hdjoint.diagnosis.model.kinematics import Kinematics, _Filter


# Values kept per cache: a fit's Jacobian moves one parameter at a time and
# comes back to its point, so keeping only the last value, a fit recomputed
# the one at its point after every column that moved it.
RECENT = 8


class Recent:
    """The last RECENT values computed, by key."""

    def __init__(self):
        self.items: OrderedDict = OrderedDict()

    def get(self, key):
        value = self.items.get(key)
        if value is not None:
            self.items.move_to_end(key)
        return value

    def put(self, key, value):
        self.items[key] = value
        self.items.move_to_end(key)
        if len(self.items) > RECENT:
            self.items.popitem(last=False)
        return value


@dataclass
class Prepared:
    """A recording with what every model evaluation needs, computed once."""
    rec: Recording
    kin: Kinematics
    t_rel: np.ndarray  # time since the start, s
    starts: np.ndarray = field(default_factory=lambda: np.array([0]))  # contiguous windows

    # Where the logged current sits against the encoder samples, s (<= 0): see
    # current_alignment.py. 0: sampled at the encoders' instant; -Ts/2: the
    # value a drive holds over the sample that follows its time stamp.
    current_shift: float = 0.0

    def __post_init__(self):
        self._smoothed: dict[int, np.ndarray] = {}
        self._currents = Recent()  # shift -> smoothed current, see _smoothed_current
        self._friction = Recent()  # law parameters -> smoothed friction, see smoothed_friction
        self._torsion = Recent()  # geometry parameters but a0 -> (its high-pass part, its rate), see _geometric_torsion
        self._loop_free = Recent()  # what the compliance model reads but the loop -> (loop-free torque, loop drive), see _loop_free
        self._torsion_basis: _TorsionBasis | None = None
        self._sharp: _Filter | None = None
        self._sharp_smoothed: dict[str, np.ndarray] = {}

    def per_window(self, func, *arrays) -> np.ndarray:
        """func over each contiguous window on its own (state and
        interpolation must not run across the jump between windows)."""
        if len(self.starts) == 1:
            return func(*arrays)
        bounds = zip(self.starts, list(self.starts[1:]) + [len(self.rec)])
        return np.concatenate([func(*(a[lo:hi] for a in arrays)) for lo, hi in bounds])

    @property
    def has_sensor(self) -> bool:
        return self.rec.tau_sensor is not None

    def smoothed(self, name: str, x: np.ndarray) -> np.ndarray:
        """A fixed signal of the recording (named) through the kinematics' smoothing filter, cached."""
        if name not in self._smoothed:
            self._smoothed[name] = self.kin.smooth(np.nan_to_num(x))
        return self._smoothed[name]

    def sharp(self) -> _Filter:
        """The transmission's filter (TORSION_RATE_SIGMA, at least 2.5 samples): the damping's rate is
        differentiated through it."""
        if self._sharp is None:
            self._sharp = _Filter(self.rec.time, TORSION_RATE_SIGMA, self.starts)
        return self._sharp

    def sharp_smoothed(self, name: str, x: np.ndarray) -> np.ndarray:
        """A fixed signal of the recording (named) through the transmission's filter, cached."""
        if name not in self._sharp_smoothed:
            self._sharp_smoothed[name] = self.sharp()(np.nan_to_num(x))
        return self._sharp_smoothed[name]

# The motor and link estimates use differentiated encoders, so they see the
# world through the kinematics' Gaussian smoothing filter: their current is smoothed the
# same way, and whatever they are compared with must be too (SMOOTHED_PARTS).
SMOOTHED_PARTS = ("motor", "link")


def _get(p: dict, name: str) -> float:
    return p[name] if name in p else parameters.table()[name].default


# Structural damping of the flexspline (Df: the plant's, beyond the paper; the
# estimator has none) acts on the rate of the torsion less the kinematic
# error. That rate lives at the torsional mode (about 50 Hz), which the 6 ms
# kinematics filter passes at 13 %: it is differentiated through a Gaussian
# of 2.5 samples at 1 kHz instead. Where the plant has Df and the model
# leaves it out, this term can be most of the transmission residual.
TORSION_RATE_SIGMA = 0.0015  # s


# The kinematic error's terms (transmission.cpp, kinematic_error): eq. (7)'s
# amplitudes, and the slots of its extra orders (<slot>_order, <slot>_a, <slot>_b).
KINEMATIC_EXTRA = tuple(slot for slot, _ in KINEMATIC_ERROR.slots)
# The kinematic error is linear in its amplitudes (a0, eq. (7)'s, the extra
# orders' a and b) once the ratio, wave numbers and orders are fixed.
KINEMATIC_AMPLITUDES = ("a0",) + KINEMATIC_EQ7 + tuple(f"{slot}_{k}" for slot in KINEMATIC_EXTRA for k in ("a", "b"))
KINEMATIC_SHAPE = ("N", "omega_l", "omega_w") + tuple(f"{slot}_order" for slot in KINEMATIC_EXTRA)
# What the torsion less the kinematic error depends on (total_torsion, kinematic_error).
GEOMETRY_PARAMETERS = KINEMATIC_SHAPE + KINEMATIC_AMPLITUDES


@dataclass
class _TorsionBasis:
    """The torsion less the kinematic error as base - amplitudes . columns, for
    one shape (KINEMATIC_SHAPE): as itself, its part above the transmission's
    filter, and its rate through that filter (VIEWS). A fit moves the
    amplitudes (a0 most often), and recomputing would run the compliance
    model and two filters over the whole run each time. a0 is an offset,
    which neither filtered view sees."""
    shape: tuple
    base: dict  # view -> the torsion with every amplitude 0
    columns: dict  # view -> (amplitude, n): the kinematic error of each unit amplitude but a0

    VIEWS = ("itself", "high_pass", "rate")

    @classmethod
    def build(cls, prep: Prepared, shape: dict) -> "_TorsionBasis":
        # The other parameters at their defaults; a rigid wave generator, no dead zone.
        zero = dict(parameters.defaults(), **shape, **{a: 0.0 for a in KINEMATIC_AMPLITUDES})
        native = parameters.for_estimator(dict(zero, Kw=1e9, hys_H=0.0, backlash=0.0, i_delay=0.0))
        rec = prep.rec
        torsion = np.nan_to_num(prep.per_window(
            lambda i, tm, tl: _compliance(native, i, tm, tl)["dtheta_f"], rec.i_m, rec.theta_m, rec.theta_l))
        unit = 1e-3  # rad, inside every amplitude's range
        units = [_core.kinematic_error(_native(dict(zero, **{a: unit})), rec.theta_m, rec.theta_l) / unit
                 for a in KINEMATIC_AMPLITUDES[1:]]
        views = [cls._views(prep, x) for x in [torsion] + units]
        return cls(tuple(shape.values()), dict(zip(cls.VIEWS, views[0])),
                   {v: np.stack([u[k] for u in views[1:]]) for k, v in enumerate(cls.VIEWS)})

    @staticmethod
    def _views(prep: Prepared, x: np.ndarray) -> tuple:
        return x, x - prep.sharp()(x), prep.sharp()(x, 1)

    def at(self, view: str, p: dict) -> np.ndarray:
        out = self.base[view].copy()
        for column, name in zip(self.columns[view], KINEMATIC_AMPLITUDES[1:]):
            if _get(p, name):  # most are off: the extra orders' slots
                out -= _get(p, name) * column
        return out - _get(p, "a0") if view == "itself" else out


def _torsion_basis(prep: Prepared, p: dict) -> _TorsionBasis:
    shape = tuple(_get(p, n) for n in KINEMATIC_SHAPE)
    if prep._torsion_basis is None or prep._torsion_basis.shape != shape:
        prep._torsion_basis = _TorsionBasis.build(prep, dict(zip(KINEMATIC_SHAPE, shape)))
    return prep._torsion_basis


def _geometric_torsion(prep: Prepared, p: dict) -> tuple[np.ndarray, np.ndarray]:
    """The torsion less the kinematic error (and before the wave generator's
    share, as the plant damps it), over the whole run: its part above the
    transmission's filter, and its rate through that filter. Recomputed
    only when the geometry changes: keyed on everything, it would run the
    compliance model over the whole run for every Jacobian column of Kf,
    Cf, Kt, ..., most of a diagnosis's time."""
    key = tuple(_get(p, n) for n in GEOMETRY_PARAMETERS if n != "a0")
    views = prep._torsion.get(key)
    if views is None:
        basis = _torsion_basis(prep, p)
        views = prep._torsion.put(key, (basis.at("high_pass", p), basis.at("rate", p)))
    return views


def torsion_less_kinematic(prep: Prepared, p: dict) -> np.ndarray:
    """The encoders' torsion theta_m/N - theta_l less the model's kinematic error (and a0), rad, whole run."""
    return _torsion_basis(prep, p).at("itself", p)


def torsion_rate(prep: Prepared, p: dict) -> np.ndarray:
    """d/dt of the torsion less the kinematic error, through the transmission's filter (cached on the geometry)."""
    return _geometric_torsion(prep, p)[1]


def sharp_transmission(prep: Prepared) -> bool:
    """Whether tau_T is seen through the transmission's filter: against a
    torque sensor it is compared sample by sample, and its damping term can
    only be seen through that filter. A cogging torque shakes the torsion at
    6 omega_m (30-100 Hz), where the filter passes 30-90 % of the rate: the
    damping torque lost there is periodic in the motor angle, and the
    kinematic error's order 6 would take it on a joint without one. The sensor goes
    through the same filter (Evaluator.reference), and so does the
    compliance model: its inputs (the torsion's high-pass part taken off
    the link angle, and the current), which the stiffness law passes
    linearly at so small an amplitude, so it runs only where the fit
    looks. Without a sensor tau_T is the reference of parts seen through
    the kinematics' 6 ms filter, which takes the same band away."""
    return prep.has_sensor


def tau_transmission(prep: Prepared, p: dict[str, float], index: np.ndarray | None = None,
                     sharp: bool | None = None) -> np.ndarray:
    """tau_T: the compliance model over the recording (NaN where the torsion
    is singular), plus the structural damping Df when p has it.

    At the encoders' instants: the current is realigned by i_delay (it enters
    through the wave generator's torque), and the compliance model runs with
    no delay line. (The estimator's delay line pairs each current with the
    angles i_delay earlier, so its output lags by i_delay: compared with a
    torque sensor sampled with the encoders, that lag would put a delay's
    worth of error into the transmission channel for Kf, Cf and eq. (7) to
    absorb, and a time delay's corrected set would fail on another recording.)

    With `index`, only those samples (and only when the model is stateless
    there: no hysteresis; otherwise the whole run, then indexed). `sharp`:
    through the transmission's filter (default: sharp_transmission)."""
    tau = _compliance_torque(prep, p, index, sharp_transmission(prep) if sharp is None else sharp)
    if not _get(p, "Df"):
        return tau
    rate = torsion_rate(prep, p)
    return tau + _get(p, "Df") * (rate if index is None else rate[index])


def hysteresis_torque(prep: Prepared, p: dict, sharp: bool = False) -> np.ndarray:
    """The Dahl hysteresis torque of the compliance model, driven by the
    torsion the compliance model sees (_loop_drive): the C++ model's own
    Dahl update over that torsion's valid samples, from z = 0 at each
    window's first (as the model runs it; zero where the torsion is
    singular). A loop switches over a torsion of H/sigma, a small fraction
    of an encoder count, so it flips with the torsional vibration: a
    modelled loop driven through the 6 ms smoothing, which takes that
    vibration away, does not follow the joint's loop; driven through the
    transmission's filter, it does."""
    H, sigma = _get(p, "hys_H"), _get(p, "hys_sigma")

    def loop(drive: np.ndarray) -> np.ndarray:
        z, valid = np.zeros(len(drive)), np.isfinite(drive)
        z[valid] = _core.dahl(np.ascontiguousarray(drive[valid]), H, sigma)
        return z
    return prep.per_window(loop, _loop_free(prep, p, sharp)[1])


# The Dahl loop's own parameters: the loop-free torque and the loop's drive do not read them.
LOOP_PARAMETERS = ("hys_H", "hys_sigma")


def _loop_free(prep: Prepared, p: dict, sharp: bool) -> tuple[np.ndarray, np.ndarray]:
    """The compliance torque without the loop, and the torsion that drives
    the loop (NaN where singular), cached by every other parameter they
    read: a fit of the loop (or of Df) alone moves neither."""
    key = (sharp, *((n, p.get(n)) for n in _compliance_reads() if n not in LOOP_PARAMETERS))
    cached = prep._loop_free.get(key)
    if cached is None:
        loop_free = dict(p, hys_H=0.0)
        elastic = _compliance_torque(prep, loop_free, None, sharp)
        cached = prep._loop_free.put(key, (elastic, _loop_drive(prep, loop_free, sharp, elastic)))
    return cached


def _loop_drive(prep: Prepared, p: dict, sharp: bool, elastic: np.ndarray) -> np.ndarray:
    """The eq. (4) torsion the compliance model drives its loop by (NaN where
    singular): through the transmission's filter against a torque sensor,
    else through the kinematics' smoothing. Against a sensor, the torsion's
    slow part is the link's torque's (_slow_torsion_from_link): where the
    torque spans a count or two, the encoders' torsion reverses with their
    quantisation and the kinematic error's residue, not with the load, and
    the loop would flip with them."""
    native = parameters.for_estimator(dict(p, i_delay=0.0))
    current, theta_m, theta_l = _compliance_inputs(prep, p, sharp)
    if not sharp:
        theta_m, theta_l = prep.smoothed("theta_m", theta_m), prep.smoothed("theta_l", theta_l)
    else:
        theta_l = theta_l + _slow_torsion_from_link(prep, p, elastic)

    def torsion(i, tm, tl):
        run = _compliance(native, i, tm, tl)
        return np.where(np.isfinite(run["tau_compliance"]), run["dtheta_f"], np.nan)
    return prep.per_window(torsion, current, theta_m, theta_l)


def _slow_torsion_from_link(prep: Prepared, p: dict, elastic: np.ndarray) -> np.ndarray:
    """What to add to the link angle so the compliance model's torsion
    takes its part within the kinematics' smoothing from the link's
    torque (tau_L, seen through that filter) instead of the encoders:
    the kinematics' smoothing of the torsion less the torsion tau_L twists
    the transmission by, read off the compliance law on this recording
    (`elastic`, the torque of the torsion through the transmission's
    filter, against that torsion, made monotone), each window on its own."""
    torsion = torsion_less_kinematic(prep, p)
    seen = torsion - _geometric_torsion(prep, p)[0]  # through the transmission's filter
    link_torsion = prep.per_window(_read_off_law, seen, elastic, np.nan_to_num(tau_link(prep, p)))
    return prep.kin.smooth(np.nan_to_num(torsion)) - link_torsion


def _read_off_law(torsion: np.ndarray, torque: np.ndarray, wanted: np.ndarray) -> np.ndarray:
    """The torsion at which the recorded torque-against-torsion law, made monotone, gives `wanted`."""
    ok = np.isfinite(torsion) & np.isfinite(torque)
    order = np.argsort(torsion[ok])
    return np.interp(wanted, np.maximum.accumulate(torque[ok][order]), torsion[ok][order])


def _compliance_inputs(prep: Prepared, p: dict, sharp: bool) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(current, theta_m, theta_l) the compliance model runs on: the current
    realigned by i_delay; through the transmission's filter, the current
    filtered and the torsion's high-pass part taken off the link angle."""
    rec = prep.rec
    current, theta_l = delayed_current(prep, _get(p, "i_delay")), rec.theta_l
    if sharp:
        current = prep.sharp()(current) if _get(p, "i_delay") else prep.sharp_smoothed("i_m", current)
        theta_l = theta_l + _geometric_torsion(prep, p)[0]  # the torsion through the filter
    return current, rec.theta_m, theta_l


def _compliance_torque(prep: Prepared, p: dict[str, float], index: np.ndarray | None = None,
                       sharp: bool = False) -> np.ndarray:
    """The estimator's compliance model (C++) at the encoders' instants, over
    the recording or at `index`: its current realigned by i_delay, no delay line."""
    if _get(p, "hys_H") > 0.0:
        tau = _loop_free(prep, p, sharp)[0] + hysteresis_torque(prep, p, sharp)
        return tau if index is None else tau[index]
    current, theta_m, theta_l = _compliance_inputs(prep, p, sharp)
    native = parameters.for_estimator(dict(p, i_delay=0.0))
    if index is not None:
        return _compliance(native, current[index], theta_m[index], theta_l[index])["tau_compliance"]
    return prep.per_window(lambda i, tm, tl: _compliance(native, i, tm, tl)["tau_compliance"],
                           current, theta_m, theta_l)


def _compliance(native: dict, current: np.ndarray, theta_m: np.ndarray, theta_l: np.ndarray) -> dict:
    """The C++ compliance model's run, split over this process's spare cores where it carries no state."""
    return _core.compliance(native, current, theta_m, theta_l, threads=threads_here())


def _native(p: dict[str, float]) -> dict[str, float]:
    """The parameters a C++ law takes (the names of the parameter table)."""
    return {k: float(v) for k, v in p.items() if k in parameters.table()}


def motor_friction(p: dict, omega: np.ndarray, t_rel: np.ndarray) -> np.ndarray:
    """Motor friction of eq. (2) with the Stribeck and drift terms: the C++ law
    the FMUs run (friction.h, drift scale max(0, 1 + Fc_drift*t))."""
    omega, t_rel = np.broadcast_arrays(np.asarray(omega, float), np.asarray(t_rel, float))
    return _core.motor_friction(_native(p), np.ascontiguousarray(omega), np.ascontiguousarray(t_rel))


def smoothed_friction(prep: Prepared, p: dict) -> np.ndarray:
    """The motor friction as the motor equation sees it through the smoothing
    filter: the law on the encoders' speed, then smoothed. Friction switches
    within a fraction of a millisecond at a reversal; its smoothed value is a
    step blurred over the filter there, while the law alone switches as
    sharply as it does; on a fast excitation that difference stands well
    above the noise in tau_M. (The law on a sharper speed would not do:
    while the motor creeps below a count per window that speed is
    quantisation, which a Stribeck term with a tiny omega_s would fit.)"""
    key = tuple(_get(p, n) for n in friction_law_parameters())
    smoothed = prep._friction.get(key)
    if smoothed is None:
        smoothed = prep._friction.put(key, prep.kin.smooth(motor_friction(p, prep.kin.omega_m, prep.t_rel)))
    return smoothed


def torque_constant_scale(prep: Prepared, p: dict, index: np.ndarray | None = None) -> np.ndarray | float:
    """Kt(t)/Kt, the torque constant's warm-up (friction.h; 1 when off), at
    `index` only if given. It changes over seconds, so it multiplies the
    smoothed current unfiltered."""
    if not _get(p, "Kt_warmup"):
        return 1.0
    t = prep.t_rel if index is None else prep.t_rel[index]
    return _core.torque_constant_scale(_native(p), np.ascontiguousarray(t, float))


def delayed_current(prep: Prepared, delay: float) -> np.ndarray:
    """The current realigned with the encoders when its measurement lags by `delay` seconds."""
    rec = prep.rec
    if delay == 0.0:
        return rec.i_m
    return prep.per_window(lambda t, i: np.interp(t + delay, t, i), rec.time, rec.i_m)


def current_charge(prep: Prepared, shift: float) -> np.ndarray:
    """The charge the current has carried, int i dt, at each encoder instant,
    the logged current read `shift` seconds later: the integral of its
    linear interpolation between time stamps, exact, per window (before the
    first sample and after the last the current is held)."""
    def charge(t, i):
        x = t + shift
        j = np.clip(np.searchsorted(t, x, side="right") - 1, 0, len(t) - 2)
        dt = np.diff(t)
        cumulative = np.concatenate(([0.0], np.cumsum(dt * (i[1:] + i[:-1]) / 2.0)))  # int i dt at each sample (trapezoids)
        u = np.clip(x - t[j], 0.0, dt[j])
        inside = cumulative[j] + i[j] * u + 0.5 * (i[j + 1] - i[j]) / dt[j] * u * u
        return inside + np.where(x < t[0], i[0] * (x - t[0]), 0.0) + np.where(x > t[-1], i[-1] * (x - t[-1]), 0.0)
    return prep.per_window(charge, prep.rec.time, prep.rec.i_m)


def _smoothed_current(prep: Prepared, delay: float) -> np.ndarray:
    """The current as the motor equation sees it: realigned by the recording's
    alignment plus the model's delay, through the smoothing filter.

    It is the smoothing filter's derivative of the charge, not the smoothed
    samples: a drive's current can alternate from sample to sample (a
    limit cycle of its speed loop on a quantised encoder), and where the
    samples' time stamps jitter,
    interpolating that alternation onto the filter's uniform grid aliases it
    into the band the filter passes, correlated with the jitter the loop
    reacts to: it would read as a current delay that grows with the
    jitter. The charge integrates the
    alternation away, and d/dt of the smoothed charge is the smoothed
    current wherever the current is smooth."""
    shift = delay + prep.current_shift  # every calibration fit reads delay 0; a delay's fit, its delay again
    current = prep._currents.get(shift)
    if current is None:
        current = prep._currents.put(shift, prep.kin.smooth(current_charge(prep, shift), 1))
    return current


def tau_motor(prep: Prepared, p: dict[str, float], index: np.ndarray | None = None) -> np.ndarray:
    """tau_M: the link-side torque the motor equation (2) implies (at `index` only, if given)."""
    rec, kin = prep.rec, prep.kin
    pick = (lambda x: x) if index is None else (lambda x: x[index])
    # The delay and the ripple pass through the smoothing filter, which needs
    # the whole run; everything else is pointwise.
    i = pick(_smoothed_current(prep, _get(p, "i_delay")))
    drive = p["Kt"] * torque_constant_scale(prep, p, index) * i - p["Jm"] * pick(kin.alpha_m) - pick(smoothed_friction(prep, p))
    if _get(p, "cog_a") or _get(p, "cog_b"):  # ripple at the motor angle's orders: through the same filter as the current
        drive = drive + pick(kin.smooth(_core.cogging_torque(_native(p), np.ascontiguousarray(rec.theta_m, float))))
    return p["N"] * drive


def tau_link(prep: Prepared, p: dict[str, float], index: np.ndarray | None = None) -> np.ndarray:
    """tau_L: the torque the link's own dynamics need (no external torque; at `index` only, if given)."""
    rec, kin = prep.rec, prep.kin
    pick = (lambda x: np.ascontiguousarray(x, float)) if index is None else (
        lambda x: np.ascontiguousarray(x[index], float))
    # The joint's own link equation (joint_plant.h), solved for the transmitted torque.
    return _core.link_torque(_native(p), pick(rec.theta_l), pick(kin.omega_l), pick(kin.alpha_l))


ESTIMATES = {"transmission": tau_transmission, "motor": tau_motor, "link": tau_link}

def depends_on(part: str) -> tuple[str, ...]:
    """Every parameter the estimate of `part` depends on, for caching it: the
    motor's and the link's follow from the effects' definitions
    (effects.part_parameters; tests/test_diagnosis_internals.py checks that
    no other parameter changes them)."""
    if part in ("motor", "link"):
        return part_parameters(part)
    return _compliance_reads() + ("Df",)  # the structural damping: added to the compliance torque


@functools.cache
def _compliance_reads() -> tuple[str, ...]:
    """What the compliance model and its loop's drive read: the estimator's
    parameters, and the link's (the drive reads the link's torque,
    _slow_torsion_from_link)."""
    own = tuple(n for n, info in parameters.table().items() if info.in_estimator())
    return own + tuple(n for n in part_parameters("link") if n not in own)
