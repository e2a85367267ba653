"""The torsion less the kinematic error (channels._geometric_torsion,
torsion_less_kinematic) is kept as a basis linear in the kinematic error's
amplitudes: a fit that moves a0, eq. (7)'s amplitudes or an extra order's
must get the same torsion, high-pass part and rate as the compliance model
run afresh, without running it again. (Running it for every move of a0 was
5 of the 22 s of CPU a 58 s recording's diagnosis took; benchmarks/bench_diagnosis.py.)"""
import numpy as np
import pytest

from hdjoint import _core
from hdjoint.diagnosis.model import torque_estimates as channels
from hdjoint.io import parameters
from hdjoint.diagnosis.model.torque_estimates import Prepared
from hdjoint.io.recording import Recording
from hdjoint.diagnosis.model.kinematics import kinematics

TS = 1e-3


def _joint(windows: int) -> Prepared:
    """A joint swinging through half a turn of the link, its flexspline
    twisting with the current, cut into `windows` contiguous windows."""
    n = 6000
    t = np.arange(n) * TS
    rng = np.random.default_rng(3)
    theta_l = 1.5 * np.sin(2 * np.pi * 0.4 * t) + 0.2 * np.sin(2 * np.pi * 3.1 * t)
    current = 2.0 * np.sin(2 * np.pi * 0.8 * t) + 0.1 * rng.standard_normal(n)
    torsion = 1e-4 * current + 2e-6 * np.sin(2 * np.pi * 48 * t)
    N = parameters.defaults()["N"]
    rec = Recording(time=t, i_m=current, theta_m=N * (theta_l + torsion), theta_l=theta_l)
    starts = np.linspace(0, n, windows, endpoint=False).astype(int)
    return Prepared(rec, kinematics(rec, starts=starts), t - t[0], starts=starts)


def _fresh(prep: Prepared, p: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The torsion, its high-pass part and its rate by the compliance model, run now."""
    geometry = {n: channels._get(p, n) for n in channels.GEOMETRY_PARAMETERS}
    native = parameters.for_estimator(dict(parameters.defaults(), **geometry, Kw=1e9, hys_H=0.0, backlash=0.0,
                                           i_delay=0.0))
    rec = prep.rec
    torsion = prep.per_window(lambda i, tm, tl: _core.compliance(native, i, tm, tl)["dtheta_f"],
                              rec.i_m, rec.theta_m, rec.theta_l)
    return torsion, torsion - prep.sharp()(torsion), prep.sharp()(torsion, 1)


def _moved(rng: np.random.Generator) -> dict:
    p = parameters.defaults()
    for name in channels.KINEMATIC_AMPLITUDES:
        p[name] = 3e-5 * rng.standard_normal()
    p.update(ke_m1_order=3.0, ke_l2_order=2.0)
    return p


@pytest.mark.parametrize("windows", [1, 3])
def test_the_basis_gives_the_compliance_models_torsion(windows):
    prep = _joint(windows)
    rng = np.random.default_rng(0)
    for _ in range(4):
        p = _moved(rng)
        torsion, high_pass, rate = _fresh(prep, p)
        got_high_pass, got_rate = channels._geometric_torsion(prep, p)
        np.testing.assert_allclose(channels.torsion_less_kinematic(prep, p), torsion, rtol=0, atol=1e-15)
        np.testing.assert_allclose(got_high_pass, high_pass, rtol=0, atol=1e-15)
        np.testing.assert_allclose(got_rate, rate, rtol=0, atol=1e-12 * np.abs(rate).max())


def test_moving_the_amplitudes_does_not_rerun_the_compliance_model(monkeypatch):
    prep = _joint(1)
    calls = []
    compliance = _core.compliance
    monkeypatch.setattr(_core, "compliance", lambda *a, **k: calls.append(1) or compliance(*a, **k))
    rng = np.random.default_rng(1)
    p = _moved(rng)
    channels._geometric_torsion(prep, p)
    first = len(calls)
    for name in ("a0", "al1", "bw2", "ke_m1_a", "ke_l2_b"):
        p = dict(p, **{name: p[name] + 1e-5})
        channels._geometric_torsion(prep, p)
        channels.torsion_less_kinematic(prep, p)
    assert len(calls) == first, f"the compliance model ran {len(calls) - first} more times for amplitudes alone"
    channels._geometric_torsion(prep, dict(p, N=p["N"] * 1.001))
    assert len(calls) == first + 1, "a new gear ratio is a new shape: its torsion is recomputed once"
