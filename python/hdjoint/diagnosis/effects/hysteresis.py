"""Hysteresis of the flexspline: a rate-independent Dahl loop on the torsion.
Its special cases: a fit that is no loop is degenerate, its gain must be its
own, and the loop is also checked as the estimator FMU runs it."""
from __future__ import annotations

import numpy as np

from hdjoint import _core
from hdjoint.diagnosis.effects.base import Effect, RecordingScale, TruthDraw
from hdjoint.io import parameters

# A Dahl loop lower than this share of the torque the torsion spans explains nothing itself.
LOOP_HEIGHT_SHARE = 1e-4


def _loop_that_never_closes(p: dict, torsion_span: float) -> str | None:
    """A Dahl loop whose switching width H/sigma exceeds a quarter of the
    recorded torsion never saturates there: it is a spring (slope sigma) on
    the smoothed torsion, not a hysteresis."""
    width = p["hys_H"] / max(p["hys_sigma"], 1e-300)
    if width <= 0.25 * torsion_span:
        return None
    return (f"the fitted loop (H = {p['hys_H']:.3g} N.m, sigma = {p['hys_sigma']:.3g} N.m/rad) switches over "
            f"{width:.2g} rad, more than a quarter of the recorded torsion ({torsion_span:.2g} rad): a spring, not a loop")


def dahl_matching_bouc_wen(A: float, beta: float, gamma: float) -> dict[str, float]:
    """The model's Dahl loop (hys_H, hys_sigma) for a Bouc-Wen loop (n = 1,
    dz = A dx - beta |dx| z - gamma dx |z|): that saturates at A/(beta + gamma)
    while loading, with initial slope A, as the Dahl law dz = sigma dx -
    sigma/H |dx| z does with H and sigma (it unloads along another branch)."""
    return {"hys_H": A / (beta + gamma), "hys_sigma": A}


class Hysteresis(Effect):
    def degenerate(self, p: dict, scale: RecordingScale) -> str | None:
        """A fit that is not a loop: one that never closes, or one too low to
        explain anything, whose gain is the refitted stiffness's (a softer
        flexspline shrinks the transmission's torque, as a dead zone does).
        A loop narrower than an encoder count is no reason by itself: the
        torsional vibration dithers the torsion over several counts, so a
        loop of about one count (2H/Kf) is still shown."""
        height = LOOP_HEIGHT_SHARE * p["Kf"] * scale.torsion_span
        if p["hys_H"] < height:
            return (f"the fitted loop (H = {p['hys_H']:.2g} N.m) is below {LOOP_HEIGHT_SHARE:g} of the torque the "
                    f"torsion spans ({p['Kf'] * scale.torsion_span:.3g} N.m): its gain is the refitted stiffness's, "
                    "not a loop")
        return _loop_that_never_closes(p, scale.torsion_span)

    def in_the_estimator(self, objective, params: dict) -> dict | None:
        """The fitted loop as the estimator FMU runs it: its compliance model
        (C++, with its own delay line) on the raw recorded current and encoder
        angles, where the diagnosis (against a sensor) drives the loop with the
        torsion through the transmission's filter. The compliance torque's
        held-out error against the sensor without and with the loop."""
        if not objective.has_sensor or not params.get("hys_H", 0.0) > 0.0:
            return None
        rec, rows = objective.rec, objective.test & np.isfinite(objective.rec.tau_sensor)

        def held_out_rms(p) -> float:
            native = parameters.for_estimator(p)
            torque = objective.prep.per_window(lambda i, tm, tl: _core.compliance(native, i, tm, tl)["tau_compliance"],
                                            rec.i_m, rec.theta_m, rec.theta_l)
            error = (torque - rec.tau_sensor)[rows]
            return float(np.std(error[np.isfinite(error)]))

        without, with_loop = held_out_rms(dict(params, hys_H=0.0)), held_out_rms(params)
        out = {"drive": "raw encoder angles (the estimator FMU)", "held_out_rms_without": round(without, 5),
               "held_out_rms_with": round(with_loop, 5), "change": round(with_loop / without - 1.0, 4)}
        if with_loop >= without:
            out["caveat"] = (f"the estimator FMU, driving the loop with the raw encoder angles, does not gain from it "
                             f"(held-out torque error {100 * out['change']:+.1f} %): it switches over "
                             f"{params['hys_H'] / params['hys_sigma']:.2g} rad of torsion, and the diagnosis fitted it "
                             "on the torsion through the transmission's filter, which the FMU does not apply")
        return out

    def plant_in_truth(self, draw: TruthDraw) -> None:
        z = draw.scaled
        if draw.rng.random() < 0.5:
            draw.form.hysteresis = "bouc_wen"  # its loop's height is A / (beta + gamma)
            draw.truth.update(bw_A=3e4 * z(), bw_beta=2e5, bw_gamma=1e5)
        else:
            draw.form.hysteresis = "dahl_power"  # height H, over the same torsion at any size
            draw.truth.update(dahl_H=0.1 * z(), dahl_rate=3e4 * z())


EFFECT = Hysteresis(
    "hysteresis", "transmission", ("hys_H", "hys_sigma"),
    "hysteresis of the flexspline: torque depends on the direction of loading (a rate-independent loop)",
    "Dahl hysteresis torque added to the elastic torque (hys_H, hys_sigma)",
    switched_by=("hys_H",), starts=({"hys_H": 0.1, "hys_sigma": 5e3}, {"hys_H": 0.3, "hys_sigma": 3e4},
                                    {"hys_H": 0.8, "hys_sigma": 1e5}),
    needs=("torque_reversals",), lookalikes=("backlash", "coulomb_friction", "wave_generator_load"),
    revealed_by="slow load reversals of several amplitudes (a loop that grows with amplitude)",
    # No detection limit: a planting follows the measured torsion, a joint's loop follows the
    # true one, and its test misses loops switching within an encoder count far beyond the size
    # at which a planting shows. A limit that does not hold is worse than none.
    stateful=True, resizes=("hys_H", "hys_sigma"), own_gain_checked=True, rank=5)
