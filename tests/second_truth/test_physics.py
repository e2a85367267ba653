"""Physics sanity of the second truth: statics, signs, energy, friction laws."""
from __future__ import annotations

import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from second_truth.controller import PDController
from second_truth.forms.coulomb import Coulomb, stribeck
from second_truth.forms.gms import GMS
from second_truth.forms.lugre import LuGre
from second_truth.forms.tan_law import TanLaw
from second_truth.joint import wg, dead_zone
from second_truth.simulate import run

from helpers import ctx, joint, truth_params

_trapz = getattr(np, "trapezoid", None) or getattr(np, "trapz")


@pytest.mark.parametrize("extra", [{}, {"Kw": 8.0, "Cw": 12.0}, {"backlash": 1.5e-4},
                                   {"harmonics": [("m", 3.0, 3e-5, -2e-5), ("l", 2.0, 1e-5, 4e-5)]}])
def test_rest_state_holds_gravity(extra):
    """At rest the flexspline carries mgl*sin(theta_l) and nothing accelerates."""
    j = joint(**extra)
    th = 0.7
    y, i0 = j.rest_state(th)
    d = j.rhs(0.0, y, i0)
    assert j.tau_f(0.0, y) == pytest.approx(j.p["mgl"] * math.sin(th), rel=1e-9)
    assert abs(d[1]) < 1e-9 and abs(d[3]) < 1e-6 and abs(d[4]) < 1e-9
    # and the holding current is what the motor equation needs: Kt*i = tau_f/N
    assert j.p["Kt"] * i0 == pytest.approx(j.p["mgl"] * math.sin(th) / j.p["N"], rel=1e-9)


def test_joint_held_by_drive_under_gravity():
    """Closed loop at a fixed reference: after 0.3 s the joint is at rest with tau_f = mgl*sin."""
    j = joint()
    Ts, D = 1e-3, 0.3
    n = int(D / Ts) + 1
    r = np.full(n, 0.9)
    nom = dict(j.p, omega_fc=1.0, motor_counts=4096.0)
    out = run(j, PDController(nom, r, np.zeros(n), np.zeros(n), Ts), D, Ts)
    y = out["states"][-1]
    assert j.tau_f(D, y) == pytest.approx(j.p["mgl"] * math.sin(y[0]), abs=0.02)
    assert abs(y[1]) < 1e-3


def test_transmitted_solves_the_wave_generator_loop():
    """tau = E(deadzone(x0 - wg(tau/N))) holds at the Newton solution."""
    j = joint(Kw=6.0, Cw=15.0, backlash=1e-4)
    for x0 in (-8e-4, -2e-4, 3e-5, 5e-4, 9e-4):
        tau, _, _ = j.transmitted(x0)
        N = j.p["N"]
        w, _ = wg(tau / N, N, 6.0, 15.0)
        xf, _ = dead_zone(x0 - w, 1e-4)
        assert tau == pytest.approx(j.stiffness.elastic(xf)[0], abs=1e-9)
        assert w != 0.0 or tau == 0.0


def test_positive_current_drives_link_positive():
    """Contract signs: Kt*i > 0 twists the flexspline positive (tau_f > 0) and turns the link positive."""
    j = joint(mgl=0.0)
    y, _ = j.rest_state(0.0)
    sol = solve_ivp(j.rhs, (0, 0.2), y, args=(1.0, 0.0), method="LSODA", max_step=1e-3, rtol=1e-7, atol=j.atol())
    yf = sol.y[:, -1]
    assert yf[0] > 0 and yf[1] > 0 and j.tau_f(0.2, yf) > 0
    # the motor leads the link: theta_m/N - theta_l > 0
    assert yf[2] > 0


def test_energy_decays_without_input():
    """A twisted joint let go (no current, no gravity, linear spring) only loses energy."""
    j = joint(forms=[TanLaw(), Coulomb(None, omega_c=0.3)], mgl=0.0, Cf=0.0, Kw=0.0)
    y, _ = j.rest_state(0.0)
    y[2] = 4e-4  # torsion
    sol = solve_ivp(j.rhs, (0, 0.3), y, args=(0.0, 0.0), method="LSODA", max_step=2e-4, rtol=1e-8,
                    atol=j.atol() * 1e-2, dense_output=True)
    t = np.linspace(0, 0.3, 600)
    Y = sol.sol(t)
    p = j.p
    terr = np.array([j.theta_err(p["N"] * (a + b), a, 0, 0)[0] for a, b in zip(Y[0], Y[2])])
    E = 0.5 * p["Jm"] * Y[3] ** 2 + 0.5 * p["Jl"] * Y[1] ** 2 + 0.5 * p["Kf"] * (Y[2] - terr) ** 2
    assert E[-1] < 0.5 * E[0]
    # the kinematic error moves the spring's rest point a little: allow a tiny rise
    assert np.all(np.diff(E) < 1e-4 * E[0])


def _integrate_friction(form, omega_of_t, T, n=2000):
    """Friction torque of a form under a prescribed motor speed."""
    p = truth_params(Fs=0.01, omega_s=5.0)
    form.bind(p)
    c = ctx(p=p)

    def f(t, z):
        c.omega_m = omega_of_t(t)
        return form.rates(c, z)

    z0 = [0.0] * form.n_states
    sol = solve_ivp(f, (0, T), z0, method="LSODA", max_step=T / n, rtol=1e-8, atol=1e-12, dense_output=True)
    t = np.linspace(0, T, n)
    F = []
    for ti in t:
        c.omega_m = omega_of_t(ti)
        F.append(form.torque(c, sol.sol(ti)))
    return t, np.array(F), p


@pytest.mark.parametrize("w", [-40.0, -3.0, 0.5, 4.0, 25.0])
def test_lugre_steady_state_is_the_stribeck_curve(w):
    t, F, p = _integrate_friction(LuGre(np.random.default_rng(1)), lambda t: w, 0.5)
    assert F[-1] == pytest.approx(math.copysign(stribeck(p, w), w), rel=1e-3)


def test_gms_steady_state_is_the_stribeck_curve():
    for w in (-20.0, 2.0, 6.0):
        t, F, p = _integrate_friction(GMS(np.random.default_rng(2)), lambda t: w, 0.5)
        assert F[-1] == pytest.approx(math.copysign(stribeck(p, w), w), rel=2e-3)


@pytest.mark.parametrize("cls", [LuGre, GMS])
def test_presliding_hysteresis_loop(cls):
    """A small back-and-forth (well inside gross sliding) gives a closed loop of non-zero area in (x, F)."""
    form = cls(np.random.default_rng(3))
    A, f = 4e-4, 2.0
    w = lambda t: A * 2 * math.pi * f * math.cos(2 * math.pi * f * t)
    t, F, p = _integrate_friction(form, w, 2.0, n=4000)
    x = A * np.sin(2 * math.pi * f * t)
    last = t >= 1.5  # the last full period
    area = abs(_trapz(F[last], x[last]))
    assert area > 0.05 * p["Fc"] * A  # a loop, not a line
    assert np.max(np.abs(F)) < 1.2 * (p["Fc"] + p["Fs"])  # presliding stays below breakaway
    # memory: at the turning points (speed 0) the force stays near its last value, where a
    # static law (Coulomb) gives 0
    k = np.argmin(np.abs(t - 1.625))  # x at its maximum, speed 0
    assert abs(F[k]) > 0.2 * p["Fc"]
    tc, Fc_, _ = _integrate_friction(Coulomb(None, omega_c=0.3), w, 2.0, n=4000)
    assert abs(Fc_[k]) < 0.05 * p["Fc"]


def test_probes_on_the_ticks_read_the_tick_states():
    """Every probe is answered, and a probe on a tick reads that tick's state (k*Ts vs t+Ts rounding)."""
    j = joint()
    Ts, D = 1e-3, 1.2  # k*Ts and (k-1)*Ts + Ts first differ in floating point at k = 1001
    n = int(round(D / Ts)) + 1
    t = np.arange(n) * Ts
    r = 0.3 + 0.2 * np.sin(2 * np.pi * 0.5 * t)
    nom = dict(j.p, omega_fc=1.0, motor_counts=4096.0)
    out = run(j, PDController(nom, r, np.gradient(r, Ts), np.gradient(np.gradient(r, Ts), Ts), Ts), D, Ts,
              probes={"tick": t, "late": t - 3.3e-4})
    assert np.allclose(out["probes"]["tick"], out["states"], rtol=0, atol=1e-9)
    assert np.all(np.isfinite(out["probes"]["late"]))
    assert np.max(np.abs(np.diff(out["probes"]["late"][:, 0]))) < 1e-3


def test_transmitted_torque_follows_the_contract_compliance():
    """Without extra forms, tau_f = tan(Cf*Kf*(theta_m/N - theta_l - theta_err))/Cf with eq. (7) as the contract writes it."""
    j = joint(harmonics=[("m", 3.0, 2e-5, 1e-5)])
    p = j.p
    rng = np.random.default_rng(5)
    for _ in range(20):
        y, _ = j.rest_state(0.0)
        y[0], y[2] = rng.uniform(-2, 2), rng.uniform(-6e-4, 6e-4)
        tl = y[0]
        tm = p["N"] * (y[0] + y[2])
        w, ww = p["omega_l"], p["omega_w"]
        terr = (p["a0"] + p["al1"] * math.cos(w * tl) + p["bl1"] * math.sin(w * tl)
                + p["aw1"] * math.cos(ww * tm) + p["bw1"] * math.sin(ww * tm)
                + p["aw2"] * math.cos(2 * ww * tm) + p["bw2"] * math.sin(2 * ww * tm)
                + 2e-5 * math.cos(3 * tm) + 1e-5 * math.sin(3 * tm))
        x = tm / p["N"] - tl - terr
        assert j.tau_f(0.0, y) == pytest.approx(math.tan(p["Cf"] * p["Kf"] * x) / p["Cf"], rel=1e-6, abs=1e-9)


@pytest.mark.parametrize("name", ["dwell_reversals", "constant_speed", "chirp"])
def test_references_are_smooth(name):
    """No corner in a reference: its acceleration (the drive's feed-forward) has no spikes."""
    from second_truth.excitations import reference
    r, rd, rdd = reference(name, 20.0, 1e-3, np.random.default_rng(4))
    assert np.max(np.abs(r)) < 1.3 and np.max(np.abs(rdd)) < 25.0
    assert np.max(np.abs(np.diff(rdd))) < 0.5  # rad/s^2 per sample
