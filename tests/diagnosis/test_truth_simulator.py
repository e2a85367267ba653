"""The independent truth of the diagnosis benchmark: independent of the
project's own joint (no C++ core, no FMU), right (the contract's equations
hold in what it simulates) and its sensor options do what they say."""
import ast
import math
from pathlib import Path

import numpy as np
import pytest

import hdjoint_truth as truth_package
from hdjoint_truth import physics
from hdjoint_truth.cases import CONTROL_CASES, EFFECT_CASES, draw
from hdjoint_truth.physics import Form
from hdjoint_truth.sensors import CurrentSensor, Encoder
from hdjoint_truth.simulate import Setup, _Plant, check_form, simulate

NOMINAL = dict(N=100.0, Kt=0.045, Jm=2.09e-5, Bm=3e-5, Fc=0.015, Kf=1e4, Cf=0.0645, Kw=10.0, Cw=10.0, a0=1e-4,
               al1=1e-4, bl1=0.5e-4, omega_l=1.0, aw1=0.6e-4, bw1=-0.4e-4, aw2=0.2e-4, bw2=0.1e-4, omega_w=2.0,
               Jl=0.15, Bl=0.05, mgl=5.0, Df=4.0)
FORBIDDEN = {"_core", "fmu_runner", "fmus", "experiments", "cases", "channels", "diagnosis", "cosim"}


def test_the_truth_imports_nothing_of_the_projects_joint():
    for path in Path(truth_package.__file__).parent.glob("*.py"):
        tree = ast.parse(path.read_text())
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.level == 2:  # from ..x import y (hdjoint itself)
                names = {node.module} if node.module else {a.name for a in node.names}
                assert not names & FORBIDDEN, f"{path.name} imports {names & FORBIDDEN} of the project's joint"
            if isinstance(node, ast.Import):
                assert not any(a.name.startswith("hdjoint.") and a.name.split(".")[1] in FORBIDDEN
                               for a in node.names), path.name


def contract_torque(p, theta_m, theta_l, tau_w):
    """CONTRACT.md eq. (3)-(8), written out here on their own."""
    dtheta = theta_m / p["N"] - theta_l
    wg = math.copysign(1.0, tau_w) / (p["Cw"] * p["N"] * p["Kw"]) * (1.0 - math.exp(-p["Cw"] * abs(tau_w)))
    wl, ww = p["omega_l"] * theta_l, p["omega_w"] * theta_m
    err = (p["a0"] + p["al1"] * math.cos(wl) + p["bl1"] * math.sin(wl) + p["aw1"] * math.cos(ww)
           + p["bw1"] * math.sin(ww) + p["aw2"] * math.cos(2 * ww) + p["bw2"] * math.sin(2 * ww))
    return math.tan(p["Cf"] * p["Kf"] * (dtheta - wg - err)) / p["Cf"]


@pytest.mark.parametrize("theta_l", [-0.9, 0.2, 1.1])
def test_static_joint_holds_gravity_through_the_contracts_compliance(theta_l):
    plant = _Plant(NOMINAL, Form(), theta_l)  # at rest in static equilibrium
    tau = plant.transmitted()
    assert tau == pytest.approx(NOMINAL["mgl"] * math.sin(theta_l), abs=1e-6)
    assert tau == pytest.approx(contract_torque(NOMINAL, plant.theta_m, plant.theta_l, tau / NOMINAL["N"]), abs=1e-6)


def test_simulated_motion_obeys_the_link_and_motor_equations():
    setup = Setup(excitation="multisine", duration=4.0, motor_encoder=Encoder(0), link_encoder=Encoder(0),
                  current_sensor=CurrentSensor(white=0.0), with_torque_sensor=False)
    form = Form(omega_fc=1.0)
    rec = simulate(NOMINAL, form, setup, NOMINAL)
    t, tau = rec.time, rec.extra["tau_joint"]
    w_l, w_m = np.gradient(rec.theta_l, t), np.gradient(rec.theta_m, t)
    a_l, a_m = np.gradient(w_l, t), np.gradient(w_m, t)
    inner = slice(1500, -50)  # after the fade-in, away from the ends of the differences
    link = NOMINAL["Jl"] * a_l + NOMINAL["Bl"] * w_l + NOMINAL["mgl"] * np.sin(rec.theta_l)
    motor = NOMINAL["N"] * (NOMINAL["Kt"] * rec.i_m - NOMINAL["Jm"] * a_m - NOMINAL["Bm"] * w_m
                            - NOMINAL["Fc"] * np.tanh(w_m / form.omega_fc))
    scale = np.std(tau[inner])
    assert scale > 0.5
    # Within 5 % of the torque's swing: the step is 0.2 ms, the differences 1 ms.
    assert np.sqrt(np.mean((link - tau)[inner] ** 2)) < 0.05 * scale
    assert np.sqrt(np.mean((motor - tau)[inner] ** 2)) < 0.05 * scale


def test_lugre_truth_keeps_the_rotors_inertia_while_sliding():
    """LuGre bristles as stiff and damped as the benchmark draws them: while
    the motor slides, the motion is the rotor's inertia and Coulomb friction.
    The integrator once took the bristle damping's slope while sliding too,
    which weighed the rotor by Jm + h*(sigma1 + sigma0*h): 2.25 Jm here, and
    every LuGre control calibrated Jm to twice its value."""
    form = Form(friction="lugre", substeps=10, lugre_sigma0=500.0)
    form.lugre_sigma1 = 2.0 * math.sqrt(form.lugre_sigma0 * NOMINAL["Jm"])
    setup = Setup(excitation="chirp", duration=6.0, motor_encoder=Encoder(0), link_encoder=Encoder(0),
                  current_sensor=CurrentSensor(white=0.0))
    rec = simulate(NOMINAL, form, setup, NOMINAL)
    t, tau = rec.time, rec.extra["tau_joint"]
    w_m = np.gradient(rec.theta_m, t)
    a_m = np.gradient(w_m, t)
    sliding = np.abs(w_m) > 3.0
    sliding[:1500] = False  # after the fade-in
    # Jm*a_m = Kt*i - Fc*sign(w) - Bm*w - tau/N: the inertia by least squares.
    drive = (NOMINAL["Kt"] * rec.i_m - NOMINAL["Fc"] * np.sign(w_m) - NOMINAL["Bm"] * w_m - tau / NOMINAL["N"])
    inertia = float(np.sum(drive[sliding] * a_m[sliding]) / np.sum(a_m[sliding] ** 2))
    assert inertia == pytest.approx(NOMINAL["Jm"], rel=0.05)


def test_transmitted_torque_follows_the_contracts_compliance_while_moving():
    """Along a trajectory, with strong structural damping and fine substeps
    (where differencing the wave generator's term once made the torque ring
    from substep to substep), tau_joint is eq. (3)-(8) of the recorded angles
    plus a damping torque much smaller than the torque itself."""
    joint = dict(NOMINAL, Df=7.0)
    setup = Setup(excitation="chirp", duration=3.0, motor_encoder=Encoder(0), link_encoder=Encoder(0))
    rec = simulate(joint, Form(substeps=8), setup, NOMINAL)
    tau = rec.extra["tau_joint"]
    law = np.array([contract_torque(joint, m, l, t / joint["N"]) for m, l, t in zip(rec.theta_m, rec.theta_l, tau)])
    # The damping torque: Df times the rate of the torsion less the kinematic error (geometry is not strain).
    strain = law / joint["Kf"]  # about the elastic torsion; its rate is what Df acts on
    damping = joint["Df"] * np.gradient(strain, rec.time)
    assert np.sqrt(np.mean((law - tau) ** 2)) < 0.15 * np.std(tau)
    assert np.sqrt(np.mean((law + damping - tau) ** 2)) < 0.5 * np.sqrt(np.mean((law - tau) ** 2))


def test_encoder_quantisers_floor_or_round_and_interpolation_error():
    x = np.linspace(-3.0, 3.0, 10001)
    step = 2 * math.pi / 4096
    floor, nearest = Encoder(4096, "floor").read(x), Encoder(4096, "round").read(x)
    assert np.all(floor <= x + 1e-15) and np.all(x - floor < step)
    assert np.max(np.abs(nearest - x)) <= step / 2 + 1e-12
    assert np.mean(x - floor) == pytest.approx(step / 2, rel=0.05)  # floor reads half a count low on average
    wobbly = Encoder(4096, "round", interpolation=0.4).read(x)
    assert np.max(np.abs(wobbly - x)) > step / 2 + 0.2 * step
    with pytest.raises(ValueError, match="rounding"):
        Encoder(4096, "ceil").read(x)


def test_current_sensor_gain_offset_and_delay():
    rng = np.random.default_rng(0)
    sensor = CurrentSensor(gain_error=0.02, offset=0.01, white=0.001)
    assert np.mean(sensor.read(np.ones(5000), 1e-3, rng)) == pytest.approx(1.03, abs=1e-3)
    step = np.r_[np.zeros(10), np.ones(10)]
    delayed = CurrentSensor(white=0.0, delay=3e-3).read(step, 1e-3, rng)
    assert np.flatnonzero(delayed > 0.5)[0] == 13


def test_sampling_jitter_shows_in_the_time_stamps_only_when_asked():
    base = dict(excitation="chirp", duration=0.5, jitter=1.5e-4)
    rec = simulate(NOMINAL, Form(substeps=8), Setup(**base, stamp_actual_times=True), NOMINAL)
    dt = np.diff(rec.time)
    assert dt.min() < 1e-3 - 5e-5 and dt.max() > 1e-3 + 5e-5 and dt.min() > 0
    assert np.all(np.abs(dt - 1e-3) <= 1.5e-4 + 1e-9)
    regular = simulate(NOMINAL, Form(substeps=8), Setup(**base), NOMINAL)
    assert np.allclose(np.diff(regular.time), 1e-3)


def test_forms_that_cannot_run_are_refused_by_name():
    with pytest.raises(ValueError, match="Heun"):
        check_form(Form(friction="lugre", integrator="heun"))
    with pytest.raises(ValueError, match="friction"):
        check_form(Form(friction="viscous"))


def test_cases_cover_every_effect_and_every_excitation_and_draw_differently_per_seed():
    from hdjoint.diagnosis.effects import EFFECTS
    present = {e for c in EFFECT_CASES for e in c.present}
    assert present == set(EFFECTS) - {"wave_generator_load"}
    assert {c.excitation for c in CONTROL_CASES} == {"paper", "multisine", "sweep", "constant_speeds", "chirp"}
    a, b = draw(EFFECT_CASES[0], 0), draw(EFFECT_CASES[0], 1)
    assert a.truth != b.truth and a.setups[0].excitation != a.setups[1].excitation
    assert physics.kinematic_error(a.truth, a.form, 1.0, 0.01) != physics.kinematic_error(a.truth, Form(), 1.0, 0.01)


@pytest.mark.parametrize("integrator", ["semi_implicit", "heun"])
def test_an_external_load_on_the_link_is_carried_by_the_joint(integrator):
    # Payload steps: 1.2 N.m pushing the link from 5 s on; the controller holds the
    # position, so the transmitted torque gives way by the payload (tau_f = load - tau_ext).
    form = Form(integrator=integrator, omega_fc=1.0, substeps=5)
    base = dict(excitation="sweep", duration=7.0, scale=0.0)
    quiet = simulate(NOMINAL, form, Setup(**base), NOMINAL)
    pushed = simulate(NOMINAL, form, Setup(**base, load="payload"), NOMINAL)
    held = (quiet.time > 6.0) & (quiet.time < 7.0)
    before = quiet.time < 5.0
    assert np.allclose(pushed.extra["tau_joint"][before], quiet.extra["tau_joint"][before])
    assert np.mean(pushed.extra["tau_joint"][held] - quiet.extra["tau_joint"][held]) == pytest.approx(-1.2, abs=0.05)
    with pytest.raises(ValueError, match="external load"):
        simulate(NOMINAL, form, Setup(**base, load="wind"), NOMINAL)


def test_parameter_errors_are_drawn_within_the_bounds_given_and_leave_the_rest_as_drawn():
    case = CONTROL_CASES[0]
    default, exact_kt = draw(case, 3), draw(case, 3, errors={"Kt": 0.0, "Kf": 0.2})
    assert exact_kt.truth["Kt"] == exact_kt.nominal["Kt"]
    assert {k: v for k, v in exact_kt.truth.items() if k not in ("Kt", "Kf")} == \
        {k: v for k, v in default.truth.items() if k not in ("Kt", "Kf")}
    # The same draw, scaled to the wider bound.
    assert exact_kt.truth["Kf"] / exact_kt.nominal["Kf"] - 1 == pytest.approx(
        2 * (default.truth["Kf"] / default.nominal["Kf"] - 1))



def test_the_open_library_laws_are_planted_as_stated_and_only_in_their_cases():
    from hdjoint_truth.cases import OPEN_LIBRARY_CASES
    form = Form(friction_ripple=(2.0, 0.2), friction_load=0.06)
    level = physics.friction_level(NOMINAL, form, 50.0, 0.0, theta_m=0.3, tau_f=-4.0)
    assert level == pytest.approx((NOMINAL["Fc"] + 0.06 * 4.0 / NOMINAL["N"]) * (1.0 + 0.2 * math.cos(0.6)))
    drawn = {c.outside: draw(c, 0, 1.0) for c in OPEN_LIBRARY_CASES}
    ripple = drawn["friction_ripple"]
    order, r = ripple.form.friction_ripple
    # Its amplitude Fc*r: 5-9 times the current's white noise in motor torque.
    times_noise = r * ripple.truth["Fc"] / (ripple.truth["Kt"] * ripple.setups[0].current_sensor.white)
    assert order == 2.0 and 5.0 <= times_noise <= 9.0
    assert drawn["kinematic_torque"].form.kinematic_torque[0] == 2.0
    assert 0.05 <= drawn["friction_load"].form.friction_load <= 0.08
    assert drawn["lugre"].form.friction == "lugre" and not drawn["lugre"].form.friction_load
    for case in EFFECT_CASES + CONTROL_CASES:
        joint = draw(case, 0, 1.0)
        assert not (joint.form.friction_ripple or joint.form.kinematic_torque or joint.form.friction_load)
