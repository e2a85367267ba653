"""Benchmark cases on the independent truth: every contract effect ID
concealed one (or two, or three) at a time, and controls with nothing
missing on every excitation kind. For each case and seed the truth's FORM
is drawn (friction law and smoothing, integrator and step, sensor chain,
jitter) along with its parameters (the nominal set off by up to 10 %), and
each joint is recorded twice with different excitations: the second
recording checks that the corrected model closes on data it never saw.

Effect sizes are the concealed ones of hdjoint.fmu.concealed_effects (about the noise and
quantisation level), jittered by +-20 % per seed. OPEN_LIBRARY_CASES plant
physics the effect library does not name, and a LuGre control (outside.py)."""
from __future__ import annotations

import zlib
from dataclasses import dataclass, field

import numpy as np

from hdjoint.diagnosis.effects import EFFECTS, TruthDraw
from hdjoint.io import parameters
from hdjoint_truth.excitations import EXCITATIONS
from hdjoint_truth.outside import LAWS
from hdjoint_truth.physics import Form
from hdjoint_truth.sensors import CurrentSensor, Encoder
from hdjoint_truth.simulate import Controller, Setup, simulate

# What the user believes may be off by up to this much, in the truth (relative).
NOMINAL_ERROR = 0.10
# The current sensor's gain error (relative) and offset (A) are drawn within
# these bounds: a Hall sensor's datasheet accuracy, what a user can state.
CURRENT_GAIN_BOUND, CURRENT_OFFSET_BOUND = 0.02, 0.01
JITTERED = ("Kt", "Jm", "Bm", "Fc", "Kf", "Cf", "Kw", "al1", "bl1", "aw1", "bw1", "aw2", "bw2", "Jl", "Bl", "mgl")
KINDS = tuple(EXCITATIONS)


@dataclass(frozen=True)
class TruthCase:
    name: str
    present: tuple[str, ...]                   # effect IDs the truth has and the nominal set lacks
    nominal_off: dict = field(default_factory=dict)  # how the nominal set switches them off
    excitation: str = ""                       # first recording's excitation ("" : drawn per seed)
    outside: str = ""                          # a law outside the effect library (outside.LAWS), planted too


def _effect(name, present, **off):
    return TruthCase(name, present, off)


EFFECT_CASES = [
    _effect("kinematic error (extra orders)", ("kinematic_error",)),
    _effect("wave generator compliance", ("wave_generator_compliance",), Kw=1e9, Cw=0.0),
    _effect("stiffness nonlinearity", ("stiffness_nonlinearity",), Cf=0.0),
    _effect("coulomb friction", ("coulomb_friction",), Fc=0.0),
    _effect("stribeck friction", ("stribeck_friction",)),
    _effect("viscous friction", ("viscous_friction",), Bm=0.0),
    _effect("hysteresis", ("hysteresis",)),
    _effect("backlash", ("backlash",)),
    _effect("cogging", ("cogging",)),
    _effect("time delay", ("time_delay",)),
    _effect("thermal drift", ("thermal_drift",)),
    _effect("gravity load", ("gravity_load",), mgl=0.0),
    _effect("link friction", ("link_friction",)),
    _effect("two: stiffness nonlinearity + link friction", ("stiffness_nonlinearity", "link_friction"), Cf=0.0),
    _effect("two: cogging + time delay", ("cogging", "time_delay")),
    _effect("three: kinematic error + hysteresis + stribeck", ("kinematic_error", "hysteresis", "stribeck_friction")),
    _effect("three: wave generator + viscous + cogging", ("wave_generator_compliance", "viscous_friction", "cogging"),
            Kw=1e9, Cw=0.0, Bm=0.0),
]
CONTROL_CASES = [TruthCase(f"control on {kind}", (), {}, kind) for kind in KINDS]
# Physics the effect library does not name (the open library's cases), and a
# friction law of another form with nothing missing (a control).
OPEN_LIBRARY_CASES = [
    TruthCase("outside: motor friction varying with the motor angle", (), outside="friction_ripple"),
    TruthCase("outside: kinematic error growing with the torque", (), outside="kinematic_torque"),
    TruthCase("outside: friction growing with the load", (), outside="friction_load"),
    TruthCase("control: LuGre friction", (), outside="lugre"),
]


@dataclass
class Joint:
    """One drawn truth: its parameters, its form, and how it is recorded."""
    truth: dict
    form: Form
    nominal: dict
    setups: list  # Setup per recording
    description: dict


def _rng(case: TruthCase, seed: int, salt: str = "") -> np.random.Generator:
    return np.random.default_rng(zlib.crc32(f"{case.name}|{seed}|{salt}".encode()))


def nominal_for(case: TruthCase) -> dict:
    """The user's belief: the defaults, the wave generator loaded by tau/N
    (as the truth's is), and the case's effects switched off."""
    return dict(parameters.defaults(), wg_load=1.0, **case.nominal_off)


def _draw_form(rng, present, rotor_inertia: float) -> Form:
    lugre = rng.random() < 0.3 or "coulomb_friction" in present and rng.random() < 0.5
    form = Form(friction="lugre" if lugre else "tanh", omega_fc=float(np.exp(rng.uniform(np.log(0.1), np.log(2.0)))),
                stribeck=str(rng.choice(["gauss", "exp"])))
    form.lugre_sigma0 = float(rng.uniform(200.0, 1000.0))
    # Bristle damping 0.5-1x critical on the rotor's nominal inertia.
    form.lugre_sigma1 = float(rng.uniform(0.5, 1.0) * 2.0 * np.sqrt(form.lugre_sigma0 * rotor_inertia))
    if not lugre and form.omega_fc >= 0.5 and rng.random() < 0.4:
        form.integrator, form.substeps = "heun", int(rng.choice([5, 8]))
    else:
        form.integrator, form.substeps = "semi_implicit", int(rng.choice([4, 5, 8])) if not lugre else 10
    return form


def _add_effect(effect: str, truth: dict, form: Form, sensor: CurrentSensor, rng, size: float = 1.0) -> None:
    """Put `effect` into the truth, in a form of its own (each effect says how:
    Effect.plant_in_truth), at a concealed size times `size` (what the effect
    does grows with it: an amplitude, a compliance, a loop's height, a lost
    motion's width; gravity has none)."""
    if effect not in EFFECTS:
        raise ValueError(f"no truth form for effect {effect!r}")
    EFFECTS[effect].plant_in_truth(TruthDraw(truth, form, sensor, rng, size))


def _draw_setup(rng, excitation: str, duration: float, seed: int, sensor: CurrentSensor) -> Setup:
    c = Controller()
    for name in ("kp", "ki", "kd"):
        setattr(c, name, getattr(c, name) * float(rng.uniform(0.8, 1.2)))
    return Setup(
        excitation=excitation, duration=duration, scale=float(rng.uniform(0.85, 1.1)), controller=c,
        motor_encoder=Encoder(4096.0, str(rng.choice(["floor", "round"])), float(rng.uniform(0.0, 0.25))),
        link_encoder=Encoder(524288.0, str(rng.choice(["floor", "round"])), float(rng.uniform(0.0, 0.25))),
        current_sensor=sensor, torque_noise=float(rng.uniform(0.01, 0.03)), jitter=float(rng.uniform(0.0, 2e-4)),
        stamp_actual_times=bool(rng.random() < 0.5), seed=seed)


def draw(case: TruthCase, seed: int, duration: float = 30.0, recordings: int = 2, size: float = 1.0,
         errors: dict[str, float] | None = None) -> Joint:
    """The truth joint of `case` for `seed`, and its recordings' setups; its
    effects at `size` times their concealed size; each JITTERED parameter off
    the nominal value by up to `errors[name]` (relative; NOMINAL_ERROR where
    not given)."""
    rng = _rng(case, seed)
    nominal = nominal_for(case)
    truth = dict(parameters.defaults())
    errors = errors or {}
    for name in JITTERED:
        bound = errors.get(name, NOMINAL_ERROR)
        truth[name] *= float(1.0 + rng.uniform(-bound, bound))
    truth["Df"] = float(rng.uniform(2.0, 8.0))  # structural damping: the nominal model has none
    form = _draw_form(rng, case.present, nominal["Jm"])
    sensor = CurrentSensor(gain_error=float(rng.uniform(-CURRENT_GAIN_BOUND, CURRENT_GAIN_BOUND)), offset=float(rng.uniform(-CURRENT_OFFSET_BOUND, CURRENT_OFFSET_BOUND)),
                           white=float(rng.uniform(0.005, 0.015)), coloured=float(rng.uniform(0.0, 0.01)),
                           colour_time=float(rng.uniform(0.005, 0.05)))
    for effect in case.present:
        _add_effect(effect, truth, form, sensor, rng, size)
    if case.outside:  # drawn after everything the other cases draw: theirs do not move
        LAWS[case.outside](truth, form, sensor, rng)
    first = case.excitation or KINDS[seed % len(KINDS)]
    others = [k for k in KINDS if k != first]
    kinds = [first] + [others[(seed + j) % len(others)] for j in range(recordings - 1)]
    setups = [_draw_setup(rng, kind, duration, 1000 * seed + j + 1, sensor) for j, kind in enumerate(kinds)]
    description = {"friction": form.friction, **({"outside": case.outside} if case.outside else {}), "omega_fc": round(form.omega_fc, 3), "integrator": form.integrator,
                   "substeps": form.substeps, "hysteresis": form.hysteresis, "thermal": form.thermal,
                   "excitations": kinds, "jitter_us": [round(s.jitter * 1e6) for s in setups]}
    return Joint(truth, form, nominal, setups, description)


def record(joint: Joint, index: int = 0):
    """Simulate the joint's recording number `index`."""
    return simulate(joint.truth, joint.form, joint.setups[index], joint.nominal)
