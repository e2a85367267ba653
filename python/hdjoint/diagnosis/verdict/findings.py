"""Turns a DiagnosisResult into the contract's findings document: where
each mismatch is (part, time, regime, angle), its kind (added, resized,
ambiguous), its evidence and p-value, the model terms and parameters with
their intervals, and the fit before and after."""
from __future__ import annotations

import numpy as np

from hdjoint import _core
from hdjoint.io import parameters
from hdjoint.estimation.metrics import error_figures
from hdjoint.diagnosis.rules import INTERVAL_Z
from hdjoint.diagnosis.verdict.cannot_tell import cannot_tell
from hdjoint.diagnosis.rules import FALSE_DISCOVERY_RATE, LOCATED_GAIN, LOCATED_Z
from hdjoint.diagnosis.search.significance import NullNoise, benjamini_hochberg, null_z, p_value
from hdjoint.diagnosis.model.kinematics import regime_filter
from hdjoint.diagnosis.model.structure import resolving_travel, scan, unresolved_orders


def _rms(x) -> float:
    x = x[np.isfinite(x)]
    return float(np.sqrt(np.mean(x * x))) if len(x) else float("nan")


def _smooth(x, samples: int):
    k = max(1, samples)
    return np.convolve(np.nan_to_num(x), np.ones(k) / k, mode="same")


def segments(t, mask, min_length: float) -> list[list[float]]:
    """Contiguous [start, end] times where mask holds, longer than min_length, longest first."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], mask.astype(int), [0]])))
    spans = [(t[a], t[min(b, len(t)) - 1]) for a, b in zip(edges[::2], edges[1::2])]
    spans = [s for s in spans if s[1] - s[0] >= min_length]
    return [[round(float(a), 4), round(float(b), 4)] for a, b in sorted(spans, key=lambda s: s[0] - s[1])]


def regimes(diag, reference) -> dict[str, np.ndarray]:
    kin = diag.prep.kin
    speed = np.abs(kin.omega_m)
    sign = np.sign(kin.omega_m)
    change = np.flatnonzero(np.diff(sign[np.abs(kin.omega_m) > 0.5]) != 0)
    near_reversal = np.zeros(len(speed), bool)
    moving = np.flatnonzero(np.abs(kin.omega_m) > 0.5)
    step = float(np.median(np.diff(diag.rec.time)))
    width = max(1, int(0.1 / step))
    for c in moving[change]:
        near_reversal[max(0, c - width): c + width] = True
    load = np.abs(reference)
    return {
        "low speed (|omega_m| < 2 rad/s)": speed < 2.0,
        "medium speed (2-20 rad/s)": (speed >= 2.0) & (speed < 20.0),
        "high speed (> 20 rad/s)": speed >= 20.0,
        "positive direction": kin.omega_m > 0.5,
        "negative direction": kin.omega_m < -0.5,
        "near speed reversals (±0.1 s)": near_reversal,
        "low load (|tau| < 1 N.m)": load < 1.0,
        "high load (|tau| > 3 N.m)": load > 3.0,
        "late in the run (last third)": diag.prep.t_rel > 2.0 * diag.prep.t_rel[-1] / 3.0,
        "early in the run (first third)": diag.prep.t_rel < diag.prep.t_rel[-1] / 3.0,
    }


def where(diag, finding) -> dict:
    channel = diag.channels_of(finding.effect.part)[0]
    before = diag.shown_residual(channel, finding.params_before)
    after = diag.shown_residual(channel, finding.params_after)
    contribution = np.nan_to_num(before - after)
    step = float(np.median(np.diff(diag.rec.time)))
    smooth = _smooth(contribution, int(0.05 / step))
    peak = np.nanmax(np.abs(smooth)) or 1.0
    mask = np.abs(smooth) > 0.5 * peak
    energy = contribution ** 2
    total = np.nansum(energy) or 1.0
    concentration = {}
    for name, m in regimes(diag, diag.reference_torque(finding.params_after)).items():
        share_time = float(np.mean(m))
        if share_time < 0.02:
            continue
        share_energy = float(np.nansum(energy[m]) / total)
        concentration[name] = round(share_energy / share_time, 2)
    top = sorted(concentration.items(), key=lambda kv: -kv[1])[:3]
    out = {
        "part": finding.effect.part,
        "channel": channel.name,
        "time_segments": segments(diag.rec.time, mask, 0.05)[:5],
        "fraction_of_time": round(float(np.mean(mask)), 3),
        "regime": {name: ratio for name, ratio in top if ratio > 1.3} or "throughout the run",
        "contribution_rms": round(_rms(contribution), 5),
    }
    if finding.orders:
        out["angle"] = [_order_record(o, diag.rec) for o in finding.orders]
    return out


def _order_record(o, rec) -> dict:
    """An order of a finding; one the travel does not resolve says so, with
    the travel and the orders it cannot tell apart (structure.unresolved_order)."""
    if o.resolved:
        return {"angle": o.angle, "order": o.order}
    travel = float(np.ptp(getattr(rec, o.angle)))
    alike = [k for k in unresolved_orders(o.angle, travel) if k >= o.order]
    return {"angle": o.angle, "order": o.order, "resolved": False,
            "note": f"{o.angle} travels {travel / (2 * np.pi):.2g} revolution: orders {alike[0]:g} to {alike[-1]:g} "
                    f"fit it alike; the lowest the model lacks stands for them (a travel of "
                    f"{resolving_travel(o.order):.2g} rad resolves order {o.order:g})"}


def fit_figures(diag, finding) -> dict:
    channel = diag.channels_of(finding.effect.part)[0]
    before = diag.shown_residual(channel, finding.params_before)
    after = diag.shown_residual(channel, finding.params_after)
    return {"channel": channel.name, "rms_before": _rms(before), "rms_after": _rms(after),
            "holdout_rms_before": _rms(before[diag.test]), "holdout_rms_after": _rms(after[diag.test])}


def remaining_structure(diag, p) -> list[dict]:
    """Held-out structure left in every channel after the accepted findings:
    binned-mean scans over regime features, each a location tested. A scan
    large enough to matter (over LOCATED_GAIN held out, z over LOCATED_Z) gets a p-value from
    the simulated null (significance.py; the bins are its regressors);
    Benjamini-Hochberg runs over every scan of every channel (the others
    count with p = 1, which only makes the correction stricter)."""
    rec, kin = diag.rec, diag.prep.kin
    # Measured regime features at the regime's time scale: at the channels' own
    # (6 ms) one they carry the very noise the residual does (a late-taken
    # sample is an error in the acceleration and, times Jm or Jl, in the
    # residual), and binning on it finds that noise again on held-out data.
    regime = regime_filter(rec, diag.prep.starts)
    reference = regime(np.nan_to_num(diag.reference_torque(p)))
    loading = np.sign(np.gradient(reference))
    speed = regime(kin.omega_m)
    angle = np.mod(rec.theta_m, 2 * np.pi)
    forward = speed > 0
    features = {
        "time": (diag.prep.t_rel, None, "s"),
        "motor speed": (speed, None, "rad/s"),
        "motor acceleration": (regime(kin.alpha_m), None, "rad/s2"),
        "torque level": (reference, None, "N.m"),
        "torque, loading vs unloading": (reference + LOADING_CODE * (loading > 0), None, "N.m", _loading_bin),
        "motor angle (one revolution)": (rec.theta_m, 2 * np.pi, "rad"),
        "link angle": (rec.theta_l, None, "rad"),
        # Each of these splits a feature in two: structure whose sign flips with the
        # direction (friction that ripples with the angle or grows with the load)
        # averages out of the feature alone.
        "torque level, by direction of motion": (reference + LOADING_CODE * forward, None, "N.m", _direction_bin),
        "motor angle (one revolution), by direction of motion": (
            angle + 2 * np.pi * forward, 4 * np.pi, "rad",
            _split_bin(2 * np.pi, 2 * np.pi, "rad", ", moving forward", ", moving back", "across both directions")),
        # A ripple whose size follows the torque: each bin's value is per N.m of it.
        "motor angle (one revolution), in proportion to the torque": (
            angle, 2 * np.pi, "rad", lambda lo, hi: f"{lo:.3g} to {hi:.3g} rad, growing with the torque",
            reference - np.mean(reference[diag.train])),
    }
    scans, p_raw = [], []
    for row, c in enumerate(diag.channels):
        r = np.nan_to_num(diag.shown_residual(c, p))
        through = kin.smooth if c.smoothed() else None
        noise = None
        for s in scan(r, features, diag.fold, diag.train, diag.test, through):
            scans.append((c, s))
            if not (s.gain.gain > LOCATED_GAIN and s.gain.z > LOCATED_Z and s.bin_index is not None):
                p_raw.append(1.0)
                continue
            if noise is None:
                noise = NullNoise(r[None, :]).replicates([0])
            bins = np.zeros((1, len(r), int(s.bin_index.max()) + 2))
            bins[0, np.arange(len(r)), s.bin_index] = 1.0 if s.modulator is None else s.modulator
            if through is not None:  # each bin's regressor as the channel sees it
                bins[0] = np.column_stack([through(column) for column in bins[0].T])
            bins[0, :, -1] = 1.0  # the scan removes the training mean first
            fit_rows = np.flatnonzero(diag.train)
            p_raw.append(p_value(s.gain.z, null_z(noise, bins, fit_rows, diag.fold, diag.test)))
    found = []
    for (c, s), p_adj in zip(scans, benjamini_hochberg(p_raw)):
        if s.gain.gain > LOCATED_GAIN and s.gain.z > LOCATED_Z and p_adj <= FALSE_DISCOVERY_RATE:
            found.append({"channel": c.name, "feature": s.feature, "held_out_gain": round(s.gain.gain, 4),
                          "z": round(s.gain.z, 1), "p_value": p_adj, "largest_at": s.peak_at})
    return found


# The torque features split in two code one side as torque + LOADING_CODE (N.m), far beyond any joint's torque.
LOADING_CODE = 1e4


def _split_bin(code: float, split_at: float, unit: str, coded: str, other: str, across: str):
    """Words for a bin (lo, hi) of a feature coded as value + `code` on one
    side of a split: coded values lie at or above `split_at`, the others below
    (an angle in [0, 2 pi) splits at its code; a torque of either sign,
    halfway to it)."""
    def words(lo: float, hi: float) -> str:
        if lo >= split_at:
            return f"{lo - code:.3g} to {hi - code:.3g} {unit}{coded}"
        if hi <= split_at:
            return f"{lo:.3g} to {hi:.3g} {unit}{other}"
        return across
    return words


_loading_bin = _split_bin(LOADING_CODE, LOADING_CODE / 2, "N.m", " while loading", " while unloading",
                          "torques across loading and unloading")
_direction_bin = _split_bin(LOADING_CODE, LOADING_CODE / 2, "N.m", ", moving forward", ", moving back",
                            "torques across both directions")


def estimator_comparison(diag, corrected) -> dict | None:
    """Torque estimators' error against the sensor with nominal vs corrected parameters."""
    if not diag.has_sensor:
        return None
    rec = diag.source  # the estimators run over the whole recording, not the analysed windows
    out = {}
    for label, p in (("nominal", diag.nominal), ("corrected", corrected)):
        try:
            est = _core.run_estimator(parameters.for_estimator(p), rec.time, rec.i_m, rec.theta_m, rec.theta_l)
        except RuntimeError as e:
            out[label] = {"error": str(e)}
            continue
        out[label] = {name: {"rms": round(f.rms, 5), "max": round(f.max, 5)} for name, f in
                      (("tau_compliance", error_figures(est["tau_compliance"], rec.tau_sensor)),
                       ("tau_ukf", error_figures(est["tau_ukf"], rec.tau_sensor)))}
    return out


def separate_by(effects) -> str:
    """The excitation that would tell look-alike effects apart, in one sentence."""
    return "To tell them apart, record " + "; ".join(f"{e.revealed_by} (shows {e.id})" for e in effects) + "."


def _interval(fit_std: dict, params: dict, name: str) -> list[float] | None:
    std = fit_std.get(name)
    if std is None or not np.isfinite(std):
        return None
    half = float(INTERVAL_Z * std)
    return [params[name] - half, params[name] + half]


def _alternative(effect: str, physics: str, share: float, gain: float, p_value: float, params: dict) -> dict:
    """One member of a look-alike set, as findings.json lists it."""
    return {"effect": effect, "physics": physics, "evidence_share": round(share, 3),
            "held_out_gain": round(gain, 5), "p_value": p_value, "parameters": params}


def _hypothesis_alternative(h, share: float) -> dict:
    return _alternative(h.effect.id, h.effect.physics, share, h.gain.gain, h.p_value,
                        {n: h.params_after[n] for n in _reported(h.fitted)})


def finding_document(result, f) -> dict:
    diag, final_params = result.objective, result.params
    out = {"effect": f.effect.id, "kind": f.kind, "p_value": f.p_value, "confidence": f.confidence,
           "where": where(diag, f), "model": f.effect.model, "fit": fit_figures(diag, f)}
    if f.resized:
        out["resized"] = True
        out["evidence"] = {"physics_left_out": f"{f.effect.physics}: in the nominal model, but mis-sized",
                           "z": {c.name: round(c.z, 2) for c in f.resized},
                           "test": "estimate against the prior (nominal +- tolerance); p two-sided, "
                                   "Bonferroni over the effect's parameters"}
        out["parameters"] = {c.name: {k: v for k, v in c.as_dict().items() if k in ("nominal", "estimate", "lo", "hi",
                                                                                   "tolerance")}
                             for c in f.resized}
        if f.alternatives:  # a look-alike the model lacks explains as much: "resized A, or B"
            own = f.resize_gain.gain
            total = own + sum(max(x.gain.gain, 0.0) for x in f.alternatives)
            out["alternatives"] = [_alternative(f.effect.id, out["evidence"]["physics_left_out"], own / total, own,
                                                f.p_value, {c.name: c.estimate for c in f.resized})] + [
                _hypothesis_alternative(x, max(x.gain.gain, 0.0) / total) for x in f.alternatives]
            out["separate_by"] = separate_by([f.effect] + [x.effect for x in f.alternatives])
        return out
    h = f.hypothesis
    out["evidence"] = {
        "physics_left_out": f.effect.physics,
        "held_out_gain": round(h.gain.gain, 5),
        "z": round(h.gain.z, 2),
        **h.pooled_evidence(),
        "p_value_raw": h.p_raw,
        "folds_improved": f"{h.gain.folds_improved}/{h.gain.folds_compared}",
        "delta_bic": round(h.delta_bic, 1),
        "runner_up": ({"effect": f.runner_up.effect.id, "held_out_gain": round(f.runner_up.gain.gain, 5)}
                      if f.runner_up else None),
    }
    out["evidence"].update(f.own_evidence or {})
    if h.seen_on:
        out["evidence"]["seen_on"] = h.seen_on
    out["parameters"] = {n: final_params[n] for n in _reported(f.fitted)}
    out["intervals"] = h.intervals or {n: _interval(result.last_fit.std, final_params, n) for n in f.fitted}
    in_estimator = f.effect.in_the_estimator(diag, final_params)
    if in_estimator:
        out["in_the_estimator"] = in_estimator
    if f.kind == "ambiguous":
        hypotheses = [h] + f.alternatives
        total = sum(max(x.gain.gain, 0.0) for x in hypotheses) or 1.0
        out["alternatives"] = [_hypothesis_alternative(x, max(x.gain.gain, 0.0) / total) for x in hypotheses]
        out["separate_by"] = separate_by([x.effect for x in hypotheses])
    return out


def calibration_correlation(result) -> dict:
    """The calibrated parameters' posterior correlations from the fit that gave their intervals ({name:
    {other: r}}, rounded; a pair that fit did not estimate together is left out: independent)."""
    fit = result.last_fit
    if fit.correlation is None:
        return {}
    names = [n for n in fit.names if n in result.calibration]
    at = {n: fit.names.index(n) for n in names}
    return {n: {m: round(float(fit.correlation[at[n], at[m]]), 4) for m in names if m != n} for n in names}


def document(result) -> dict:
    diag = result.objective
    if result.findings:
        verdict = "missing_physics"
    else:
        verdict = "unexplained" if result.unexplained else "consistent"
    recordings = [{"path": r.path, "samples": len(r), "duration": r.duration} for r in diag.recordings]
    doc = {
        "verdict": verdict,
        "findings": [finding_document(result, f) for f in result.findings],
        "params": result.params,
        "calibration": {n: c.as_dict() for n, c in result.calibration.items()},
        "calibration_correlation": calibration_correlation(result),
        "beyond_tolerance": [c.name for c in result.beyond_tolerance],
        "not_testable": result.not_testable,
        "orders_not_found": result.orders_not_found,
        "hypotheses_tested": result.tested,
        "false_discovery_rate": FALSE_DISCOVERY_RATE,
        "unexplained": result.unexplained,
        "cannot_tell": cannot_tell(result),
        "detection_limits": [x.as_dict() for x in result.limits],
        "located": result.located,
        "noise": {c: round(s, 6) for c, s in result.sigma.items()},
        "accuracy": result.accuracy.as_dict() if result.accuracy else None,
        "estimator": estimator_comparison(diag, result.params),
        "recording": dict(recordings[0], torque_sensor=diag.has_sensor, analysed_samples=len(diag.rec),
                          current_alignment=result.current_alignment),
    }
    if len(recordings) > 1:
        doc["recordings"] = recordings
    if verdict == "consistent" and doc["cannot_tell"]:
        doc["verdict_note"] = ("consistent as far as this recording can tell; it cannot tell " +
                               ", ".join(x.get("effect") or x["parameter"] for x in doc["cannot_tell"]))
    return doc


def _finite(x: float, digits: int) -> float | None:
    return round(float(x), digits) if np.isfinite(x) else None


def _reported(fitted) -> list[str]:
    """The fitted parameters, and the order of each angle-order slot among them (ke_m1_a -> ke_m1_order)."""
    table = parameters.table()
    slots = [n[:-2] + "_order" for n in fitted if n.endswith(("_a", "_b")) and n[:-2] + "_order" in table]
    return list(dict.fromkeys(list(fitted) + slots))
