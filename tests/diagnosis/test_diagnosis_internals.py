"""Pieces of the diagnosis that must agree with each other exactly."""
import numpy as np
import pytest

from hdjoint.fmu.concealed_effects import CASES, nominal_for, record
from hdjoint.diagnosis.model.prepare import prepare


@pytest.fixture(scope="module")
def diag():
    case = CASES[0]
    return prepare(record(case, duration=4.0), nominal_for(case))


@pytest.mark.parametrize("extra", [{}, {"hys_H": 0.2, "hys_sigma": 2e4}, {"i_delay": 2e-3}])
def test_residual_on_the_fit_sample_equals_the_full_residual_there(diag, extra):
    p = dict(diag.nominal, **extra)
    for channel in diag.channels:
        full = diag.eval.residual(channel, p)[diag.fit_index]
        sampled = diag.eval.residual_at(channel, p, diag.fit_index)
        np.testing.assert_array_equal(sampled, full)


def test_blocks_alternate_and_cover_the_run(diag):
    assert diag.train.any() and diag.test.any()
    # Every fifth of the run has both fitting and held-out samples.
    for part in np.array_split(np.arange(len(diag.rec)), 5):
        assert diag.train[part].any() and diag.test[part].any()


@pytest.mark.parametrize("part", ["transmission", "motor", "link"])
def test_estimates_depend_on_no_parameter_outside_their_cache_key(diag, part):
    """The evaluator reuses an estimate while the parameters in depends_on(part)
    are unchanged: no other parameter may change it, or the cache goes stale."""
    from hdjoint.io import parameters
    from hdjoint.diagnosis.model.torque_estimates import ESTIMATES, depends_on
    base = ESTIMATES[part](diag.prep, diag.nominal)
    for name, info in parameters.table().items():
        if name in depends_on(part):
            continue
        value = diag.nominal.get(name, info.default)
        moved = value * 1.3 + 1e-3 if info.min <= value * 1.3 + 1e-3 <= info.max else info.min
        changed = ESTIMATES[part](diag.prep, dict(diag.nominal, **{name: moved}))
        np.testing.assert_array_equal(changed, base, err_msg=f"{part} estimate depends on {name}")


@pytest.mark.parametrize("sharp", [False, True])
def test_the_loop_free_torque_and_drive_depend_on_nothing_outside_their_cache_key(diag, sharp):
    """A hysteresis fit reuses the loop-free torque and the loop's drive while
    the parameters the compliance model reads (but the loop's) are unchanged:
    no other parameter may change them (each value computed afresh here)."""
    from hdjoint.io import parameters
    from hdjoint.diagnosis.model.torque_estimates import LOOP_PARAMETERS, Recent, _compliance_reads, _loop_free

    def fresh(p):
        diag.prep._loop_free = Recent()
        return np.concatenate(_loop_free(diag.prep, p, sharp))
    p = dict(diag.nominal, hys_H=0.2, hys_sigma=2e4)
    base = fresh(p)
    for name, info in parameters.table().items():
        if name in _compliance_reads() and name not in LOOP_PARAMETERS:
            continue
        value = p.get(name, info.default)
        moved = value * 1.3 + 1e-3 if info.min <= value * 1.3 + 1e-3 <= info.max else info.min
        np.testing.assert_array_equal(fresh(dict(p, **{name: moved})), base, err_msg=f"depends on {name}")


def test_every_effect_of_the_library_has_its_parameters_in_the_model():
    """The diagnosis skips an effect whose parameters the model lacks; in this
    build every effect must be testable, so a typo cannot drop one silently."""
    from hdjoint.io import parameters
    from hdjoint.diagnosis.effects import EFFECTS
    from hdjoint.diagnosis.model.torque_estimates import KINEMATIC_EXTRA
    table = parameters.table()
    for effect in EFFECTS.values():
        for name in effect.params:
            assert name in table, f"{effect.id}: no parameter {name}"
        for start in effect.starts:
            assert set(start) <= set(effect.params), f"{effect.id}: a start sets a parameter it does not fit"
    for slot in KINEMATIC_EXTRA:
        assert {f"{slot}_order", f"{slot}_a", f"{slot}_b"} <= set(table)
    assert {"cog_order", "cog_a", "cog_b"} <= set(table)


def test_the_transmission_estimate_does_not_lag_by_the_current_delay(diag):
    """i_delay is the current's delay behind the encoders: tau_T is compared with
    a torque sensor sampled with the encoders, so it must not lag by it (the
    estimator's delay line did: a 2 ms delay put its lag into the transmission
    channel, and Kf, Cf and eq. (7) absorbed it). With the wave generator
    loaded by tau/N the current does not enter tau_T at all."""
    from hdjoint.diagnosis.model.torque_estimates import tau_transmission
    p = dict(diag.nominal, wg_load=1.0)
    np.testing.assert_array_equal(tau_transmission(diag.prep, dict(p, i_delay=2e-3)), tau_transmission(diag.prep, p))
    # With the motor current loading it, the current is the one realigned with the encoders.
    p = dict(diag.nominal, wg_load=0.0)
    late = tau_transmission(diag.prep, dict(p, i_delay=2e-3))
    assert np.nanmax(np.abs(late - tau_transmission(diag.prep, p))) > 0


def test_the_torsion_rate_is_reused_across_non_geometric_parameters_and_stays_exact(diag):
    """The damping's torsion rate depends on the geometry (N, eq. (7), its
    extra orders) alone: it is recomputed only when that changes, and the
    reused rate is the one the whole parameter set gives."""
    from hdjoint.diagnosis.model import torque_estimates as channels
    from hdjoint.io import parameters
    p = dict(diag.nominal, Df=4.0)
    first = channels.torsion_rate(diag.prep, p)
    moved = dict(p, Kf=0.8 * p["Kf"], Cf=2.0 * p.get("Cf", 0.0) + 1e-3, Kt=1.1 * p["Kt"], Kw=7.0, Cw=3.0)
    assert channels.torsion_rate(diag.prep, moved) is first  # reused, not recomputed
    full = parameters.for_estimator(dict(moved, Kw=1e9, hys_H=0.0, backlash=0.0, i_delay=0.0))
    rec = diag.prep.rec
    torsion = channels._core.compliance(full, rec.i_m, rec.theta_m, rec.theta_l)["dtheta_f"]
    exact = diag.prep.sharp()(np.nan_to_num(torsion), 1)
    # (what differs is the rigid wave generator's 1e-11 rad left at Kw = 1e9, with Kt at its default)
    np.testing.assert_allclose(first, exact, rtol=0, atol=1e-6 * np.std(exact))
    assert channels.torsion_rate(diag.prep, dict(moved, al1=3e-4)) is not first  # geometry: recomputed


def test_the_damping_torque_of_a_fast_torsion_ripple_leaves_no_transmission_residual():
    """A torsion ripple at 57 Hz (a cogging order 6 at 60 rad/s of motor speed)
    is damped by Df: the sensor reads Df times its exact rate. The model's
    rate passes through the transmission's filter (2.5 samples: 67 % at
    57 Hz), and so must the sensor and the compliance torque it is compared
    with: before they did, 33 % of the damping torque stayed in the channel,
    periodic in the motor angle, where the kinematic error's order 6 took it."""
    from hdjoint import _core
    from hdjoint.io import parameters
    from hdjoint.io.recording import Recording
    p = dict(parameters.defaults(), a0=0.0, al1=0.0, bl1=0.0, aw1=0.0, bw1=0.0, aw2=0.0, bw2=0.0, Kw=1e9,
             Df=5.0)
    t = np.arange(0.0, 4.0, 1e-3)
    theta_m = 60.0 * t
    torsion = 1e-4 * np.sin(2 * np.pi * 0.5 * t) + 2e-6 * np.sin(6 * theta_m)
    rate = 1e-4 * np.pi * np.cos(2 * np.pi * 0.5 * t) + 2e-6 * 360.0 * np.cos(6 * theta_m)
    theta_l = theta_m / p["N"] - torsion
    i_m = np.zeros_like(t)
    elastic = _core.compliance(parameters.for_estimator(p), i_m, theta_m, theta_l)["tau_compliance"]
    rec = Recording(time=t, i_m=i_m, theta_m=theta_m, theta_l=theta_l, tau_sensor=elastic + p["Df"] * rate)
    diag = prepare(rec, p)
    channel = next(c for c in diag.channels if c.name == "transmission")
    residual = diag.eval.residual(channel, p)[diag.used]
    ripple = p["Df"] * 2e-6 * 360.0 / np.sqrt(2)  # RMS of the ripple's damping torque, N.m
    assert np.sqrt(np.nanmean(residual ** 2)) < 0.02 * ripple
