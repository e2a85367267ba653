"""The verdict's absolute yardstick: each channel's noise floor from what the
sensors resolve, the accuracy the user asks for, and the residual's size
against both.

The fit's noise (objective.py) is the residual's own RMS: it weighs the
channels against each other and against the priors, and a grossly wrong
model widens it until nothing stands out. The verdict therefore also
compares the corrected model's held-out residual, in N.m, with:

  floor     what the sensors alone would leave: encoder quantisation
            (motor_counts, link_counts; q/sqrt(12) per reading) through the
            stiffness and, differentiated twice, the inertias; the current's
            and the torque sensor's noise measured in the recording's own
            high-frequency band or at standstill (or stated), through the
            channel's smoothing filter and N*Kt;
  accuracy  the user's stated accuracy (N.m), by default
            rules.ACCURACY_SHARE of the torque span, at most
            rules.MAX_MISS_SHARE of it.

A channel misses what its residual holds beyond its floor
(sqrt(rms^2 - floor^2)); a miss beyond the accuracy is `unexplained`
structure with its size, where it is largest and what would attribute it.
"""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdjoint.diagnosis.model.residual_channels import Channel
from hdjoint.diagnosis.effects import EFFECTS
from hdjoint.diagnosis.verdict.findings import regimes, segments
from hdjoint.diagnosis.model.kinematics import regime_filter
from hdjoint.diagnosis.fit.objective import Objective
from hdjoint.io import parameters
from hdjoint.diagnosis.rules import ACCURACY_SHARE, MAX_MISS_SHARE, STANDSTILL_SAMPLES, TORQUE_SPAN_PERCENTILES

MAD_TO_STD = 1.4826  # a normal's standard deviation over its median absolute deviation


def high_band_noise(x: np.ndarray) -> float:
    """The white noise of a sampled signal from its second differences (std
    sqrt(6) sigma for white noise; a smooth motion adds almost nothing),
    robust to steps and spikes through the median absolute deviation."""
    x = x[np.isfinite(x)]
    if len(x) < 3:
        return 0.0
    d2 = x[2:] - 2.0 * x[1:-1] + x[:-2]
    return float(MAD_TO_STD * np.median(np.abs(d2 - np.median(d2))) / math.sqrt(6.0))


def standstill_noise(x: np.ndarray, still: np.ndarray) -> float | None:
    """The scatter of `x` about its mean in each run of `still` samples
    (at least STANDSTILL_SAMPLES long), pooled; None without such a run."""
    edges = np.flatnonzero(np.diff(np.concatenate([[0], still.astype(int), [0]])))
    pieces = [x[a:b] - np.mean(x[a:b]) for a, b in zip(edges[::2], edges[1::2]) if b - a >= STANDSTILL_SAMPLES]
    if not pieces:
        return None
    r = np.concatenate(pieces)
    return float(np.sqrt(np.mean(r * r)))


def measured_noise(x: np.ndarray, still: np.ndarray, stated: float | None) -> tuple[float, str]:
    """A sensor's noise (its units) and where it comes from: the stated
    figure, else the smaller of the high-band and the standstill estimate
    (each is an upper bound: motion adds to both)."""
    if stated is not None:
        return float(stated), "stated"
    band = high_band_noise(x)
    rest = standstill_noise(x, still)
    if rest is not None and rest < band:
        return rest, "standstill"
    return band, "high-frequency band"


def torque_span(objective: Objective, p: dict) -> float:
    """The torque the joint carries on the analysed samples (between the
    TORQUE_SPAN_PERCENTILES), N.m: the sensor's, or without one the
    current's N*Kt*i_m."""
    torque = objective.rec.tau_sensor if objective.has_sensor else p["N"] * p["Kt"] * objective.rec.i_m
    torque = torque[objective.used & np.isfinite(torque)]
    if len(torque) == 0:
        return 0.0
    lo, hi = np.percentile(torque, TORQUE_SPAN_PERCENTILES)
    return float(hi - lo)


@dataclass(frozen=True)
class ChannelAccuracy:
    channel: str
    rms: float          # held-out residual at the corrected set, N.m
    floor: float        # what the sensors alone leave, N.m
    floor_parts: dict   # the floor's contributions, N.m
    miss: float         # sqrt(rms^2 - floor^2), N.m
    allowed: float      # the accuracy asked for, N.m

    @property
    def within(self) -> bool:
        return self.miss <= self.allowed

    def as_dict(self, span: float) -> dict:
        return {"rms": _r(self.rms), "floor": _r(self.floor), "floor_parts": {k: _r(v) for k, v in self.floor_parts.items()},
                "miss": _r(self.miss), "miss_share_of_span": _r(self.miss / span if span > 0 else math.inf),
                "allowed": _r(self.allowed), "within": self.within}


@dataclass(frozen=True)
class Accuracy:
    span: float                  # N.m
    allowed: float               # N.m
    allowed_source: str
    noise: dict                  # sensor -> {"value", "unit", "source"}
    channels: list[ChannelAccuracy]
    beyond: list[dict]           # unexplained entries for the channels that miss more than allowed

    def as_dict(self) -> dict:
        return {"torque_span": _r(self.span), "allowed": _r(self.allowed), "allowed_source": self.allowed_source,
                "sensor_noise": self.noise, "channels": {c.channel: c.as_dict(self.span) for c in self.channels}}


def _r(x: float) -> float | None:
    return round(float(x), 6) if np.isfinite(x) else None


def _filter_gains(objective: Objective) -> tuple[float, float]:
    """White noise through the kinematics' smoothing filter: the gain on a
    signal, and on its second derivative (per rad of reading, 1/s^2)."""
    piece = objective.prep.kin.smooth.pieces[0]
    g, _, d2 = piece.kernels
    return float(np.sqrt(np.sum(g * g))), float(np.sqrt(np.sum(d2 * d2))) / piece.step ** 2


def floors(objective: Objective, p: dict, noise: dict) -> dict[str, dict[str, float]]:
    """Per channel, the floor's contributions (N.m) through the model's gains at `p`."""
    smooth_gain, accel_gain = _filter_gains(objective)
    q_m = parameters.encoder_step(p["motor_counts"]) / math.sqrt(12.0)
    q_l = parameters.encoder_step(p["link_counts"]) / math.sqrt(12.0)
    # The spring's local stiffness (eq. (5) stiffens with torque), RMS over the run's reference torque.
    reference = np.nan_to_num(objective.reference_torque(p))[objective.used]
    stiffness = float(np.sqrt(np.mean((p["Kf"] * (1.0 + (p["Cf"] * reference) ** 2)) ** 2))) if len(reference) else p["Kf"]
    current = noise["i_m"]["value"]
    sensor = noise["tau_sensor"]["value"] if "tau_sensor" in noise else 0.0
    out = {}
    for c in objective.channels:
        filtered = c.smoothed()
        parts = {}
        for side in (c.reference, c.part):
            if side == "transmission":
                # Quantisation is not white at low speed (a reading stays put): no filter gain.
                parts["encoders through the stiffness"] = stiffness * math.hypot(q_m / p["N"], q_l)
            elif side == "motor":
                parts["current through N*Kt"] = p["N"] * p["Kt"] * current * smooth_gain
                parts["motor encoder through N*Jm"] = p["N"] * p["Jm"] * q_m * accel_gain
            elif side == "link":
                parts["link encoder through Jl"] = p["Jl"] * q_l * accel_gain
            elif side == "sensor":
                parts["torque sensor"] = sensor * (smooth_gain if filtered else 1.0)
        out[c.name] = parts
    return out


def _largest_at(objective: Objective, channel: Channel, r: np.ndarray, p: dict) -> str:
    """Where the residual is largest: its longest stretches above half its
    peak (at the regime's time scale) and the regimes it concentrates in."""
    smooth = regime_filter(objective.rec, objective.prep.starts)(np.nan_to_num(r))
    peak = float(np.max(np.abs(smooth))) or 1.0
    spans = segments(objective.rec.time, np.abs(smooth) > 0.5 * peak, 0.05)[:3]
    energy = np.nan_to_num(r) ** 2
    total = float(np.sum(energy)) or 1.0
    concentration = []
    for name, m in regimes(objective, objective.reference_torque(p)).items():
        if np.mean(m) >= 0.02:
            ratio = float(np.sum(energy[m]) / total) / float(np.mean(m))
            if ratio > 1.3:
                concentration.append((ratio, name))
    where = "t = " + ", ".join(f"{a:g}-{b:g} s" for a, b in spans) if spans else "throughout the run"
    if concentration:
        where += "; " + ", ".join(f"{name} x{ratio:.1f}" for ratio, name in sorted(concentration, reverse=True)[:2])
    return where


def _record_to_attribute(objective: Objective, channel: Channel, not_testable: list[dict]) -> str:
    """What recording would attribute a channel's miss: the excitations of
    the effects of its parts this recording could not test, and a torque
    sensor when there is none (it tells which side misses it)."""
    parts = channel.parts()
    asks = [f"{EFFECTS[n['effect']].revealed_by} ({n['effect']})" for n in not_testable
            if n["effect"] in EFFECTS and EFFECTS[n["effect"]].part in parts]
    if not objective.has_sensor:
        asks.append("a torque sensor's column, which tells which side of the channel misses it")
    return "; ".join(asks) or "a longer recording over a wider motion and load range"


def accuracy(objective: Objective, p: dict, not_testable: list[dict], stated_accuracy: float | None = None,
             stated_noise: dict | None = None) -> Accuracy:
    """Each channel's held-out residual at the corrected set `p` against its
    floor and the accuracy asked for (stated, N.m, or ACCURACY_SHARE of the
    torque span; never more than MAX_MISS_SHARE of it)."""
    stated_noise = stated_noise or {}
    rec = objective.rec
    still = objective.eval.motor_rest
    value, source = measured_noise(rec.i_m, still, stated_noise.get("i_m"))
    noise = {"i_m": {"value": _r(value), "unit": "A", "source": source}}
    if objective.has_sensor:
        value, source = measured_noise(rec.tau_sensor, still, stated_noise.get("tau_sensor"))
        noise["tau_sensor"] = {"value": _r(value), "unit": "N.m", "source": source}
    span = torque_span(objective, p)
    cap = MAX_MISS_SHARE * span
    if stated_accuracy is None:
        allowed, allowed_source = ACCURACY_SHARE * span, f"default: {100 * ACCURACY_SHARE:g} % of the torque span"
    elif stated_accuracy > cap:
        allowed, allowed_source = cap, (f"stated {stated_accuracy:g} N.m, held to {100 * MAX_MISS_SHARE:g} % "
                                        "of the torque span")
    else:
        allowed, allowed_source = float(stated_accuracy), "stated"
    parts = floors(objective, p, noise)
    rows, beyond = [], []
    for c in objective.channels:
        r = objective.shown_residual(c, p)
        held = r[objective.test & np.isfinite(r)]
        rms = float(np.sqrt(np.mean(held * held))) if len(held) else 0.0
        floor = math.sqrt(sum(v * v for v in parts[c.name].values()))
        row = ChannelAccuracy(c.name, rms, floor, parts[c.name], math.sqrt(max(rms * rms - floor * floor, 0.0)),
                              allowed)
        rows.append(row)
        if row.within:
            continue
        share = row.miss / span if span > 0 else math.inf
        beyond.append({
            "channel": c.name,
            "feature": (f"its size: {row.miss:.3g} N.m RMS held out beyond the sensors' floor ({row.floor:.2g} N.m), "
                        f"{100 * share:.0f} % of the {span:.3g} N.m torque span (allowed {allowed:.3g} N.m)"),
            "size_Nm": _r(row.miss), "share_of_span": _r(share),
            "held_out_gain": _r(1.0 - (floor * floor + allowed * allowed) / (rms * rms)) if rms > 0 else None,
            "z": None, "p_value": None,
            "largest_at": _largest_at(objective, c, r, p),
            "record": _record_to_attribute(objective, c, not_testable)})
    return Accuracy(span, allowed, allowed_source, noise, rows, beyond)
