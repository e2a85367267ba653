"""Residual channels: which two torque estimates each compares (with a sensor,
the sensor against each part; without one, the encoders' transmission
against the motor and the link), and the Evaluator that turns a parameter
set into those residuals on the analysed samples."""
from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from hdjoint.diagnosis.model.motor_rest import motor_at_rest
from hdjoint.diagnosis.model.torque_estimates import ESTIMATES, SMOOTHED_PARTS, Prepared, Recent, depends_on, sharp_transmission


@dataclass
class Channel:
    """A residual between two torque estimates: reference minus model part."""
    name: str
    reference: str  # "sensor" or a part
    part: str       # the part whose estimate is subtracted
    # The parameter the channel's noise scales with (Objective.noise_scale),
    # when neither side is tied to a measured torque (a sensor, the current).
    scales_with: str | None = None

    def parts(self) -> set[str]:
        return {self.part} | ({self.reference} - {"sensor"})

    def smoothed(self) -> bool:
        """Whether the channel compares through the kinematics' smoothing
        filter: either side is a part seen through it, so both must be."""
        return bool(self.parts() & set(SMOOTHED_PARTS))

    def smooths_part(self) -> bool:
        """Whether the part's estimate goes through that filter: its
        reference is seen through it and the part is not (without a sensor,
        the transmission against the motor or the link)."""
        return self.reference in SMOOTHED_PARTS and self.part not in SMOOTHED_PARTS


def channels_for(has_sensor: bool) -> list[Channel]:
    if has_sensor:
        return [Channel("transmission", "sensor", "transmission"), Channel("motor", "sensor", "motor"),
                Channel("link", "sensor", "link")]
    # Without a sensor the transmission (encoders) is the reference: its
    # quantisation noise is far below the motor's (current, acceleration).
    # The link's side is the link's motion, the other the encoders' torsion:
    # every term of it scales with the joint's torque scale, its noise (the
    # link's acceleration) with Jl.
    return [Channel("motor vs transmission", "motor", "transmission"),
            Channel("link vs transmission", "link", "transmission", scales_with="Jl")]



TORSION_VIEW = "the encoders' torsion (no torque sensor)"



OFFSET_FREE_PARTS = {"motor", "link"}


# The offset a current sensor carries, as a share of the largest current it
# measures in the recording: Hall-effect current transducers state an offset
# of 0.1-1 % of their nominal current (and a drift of as much with
# temperature), and a drive's sensor is sized for its peak current.
CURRENT_OFFSET_SHARE = 0.02


def mean_allowance(channel: Channel, p: dict, largest_current: float) -> float:
    """How much of its mean (N.m) `channel` is compared free of: all of it
    (inf), none (0), or what the current sensor's offset can give.

    Against a torque sensor: all of the motor's and link's channels' (the
    sensor's offset and the current's). Without one the motor's channel
    alone, up to N*Kt times CURRENT_OFFSET_SHARE of the largest current
    (`largest_current`, A): the current's offset N*Kt*i_0 is the motor
    side's alone, while a0, the transmission's constant, is shared by both
    channels. Held to one a0, the link channel would take the opposite
    offset and bend its gravity term to it. Only up to a sensor's offset:
    freed of all of it, the motor channel would let a0 take a static link
    torque and hide gravity. The link channel keeps its mean (a0 owns it),
    so a load that never changes sign stays visible there.
    benchmarks/sensorless_controls.py measures this on controls without a
    sensor."""
    if channel.reference == "sensor":
        return math.inf if channel.parts() & OFFSET_FREE_PARTS else 0.0
    if "motor" in channel.parts():
        return abs(p["N"] * p["Kt"]) * CURRENT_OFFSET_SHARE * largest_current
    return 0.0


def _without_mean(r: np.ndarray, over: np.ndarray, allowance: float) -> np.ndarray:
    """`r` less the mean of `over` (the samples it is taken over), clipped to +-allowance."""
    return r - float(np.clip(_finite_mean(over), -allowance, allowance))


class Evaluator:
    """Torque estimates and channel residuals for a parameter set, with the
    recent estimates of parts whose parameters did not change reused. `offset_rows`:
    the samples whose mean a channel is compared free of (mean_allowance;
    default: every finite sample). A channel with the motor's estimate
    compares nothing where the motor rests (motor_rest.py): 0 there."""

    def __init__(self, prep: Prepared, channels: list[Channel], offset_rows: np.ndarray | None = None):
        self.prep = prep
        self.channels = channels
        self.offset_rows = offset_rows
        self.motor_rest = motor_at_rest(prep.kin, prep.rec.time, prep.starts)
        self._cache: dict[str, Recent] = {}  # slot (a part, its smoothed or indexed estimate) -> recent values
        self.part_params = {part: depends_on(part) for part in ESTIMATES}
        current = np.abs(prep.rec.i_m[np.isfinite(prep.rec.i_m)])
        self.largest_current = float(np.percentile(current, 98)) if len(current) else 0.0

    def estimate(self, part: str, p: dict) -> np.ndarray:
        if part == "sensor":
            return self.prep.rec.tau_sensor
        key = tuple(p.get(n, 0.0) for n in self.part_params[part]) + (self.prep.current_shift,)
        recent = self._recent(part)
        value = recent.get(key)
        return value if value is not None else recent.put(key, ESTIMATES[part](self.prep, p))

    def _recent(self, slot: str) -> Recent:
        return self._cache.setdefault(slot, Recent())

    def reference(self, channel: Channel, p: dict) -> np.ndarray:
        """The channel's reference over the whole run, through the smoothing
        filter when the part it is compared with sees the world through it."""
        reference = self.estimate(channel.reference, p)
        if channel.part == "transmission" and channel.reference == "sensor" and sharp_transmission(self.prep):
            return self.prep.sharp_smoothed("tau_sensor", reference)
        if channel.part in SMOOTHED_PARTS and channel.reference not in SMOOTHED_PARTS:
            if channel.reference == "sensor":
                return self.prep.smoothed("tau_sensor", reference)
            return self.prep.kin.smooth(np.nan_to_num(reference))
        return reference

    def compared(self, channel: Channel) -> np.ndarray | None:
        """Where `channel` compares its estimates (None: everywhere)."""
        return ~self.motor_rest if "motor" in channel.parts() and self.motor_rest.any() else None

    def compared_by_channel(self) -> np.ndarray | None:
        """(channel, sample): where each channel compares (None: everywhere in every channel)."""
        masks = [self.compared(c) for c in self.channels]
        if all(m is None for m in masks):
            return None
        return np.stack([np.ones(len(self.motor_rest), bool) if m is None else m for m in masks])

    def part_estimate(self, channel: Channel, p: dict) -> np.ndarray:
        """The estimate `channel` subtracts, through the smoothing filter when
        its reference is seen through it (Channel.smooths_part). Without a
        sensor, the transmission's unsmoothed torque against the motor's
        smoothed one would leave tau_T's band above the filter in the
        residual, which a softer spring shrinks: calibration would bias Kf
        low to make up for it (benchmarks/sensorless_controls.py reports
        where calibration puts Kf)."""
        value = self.estimate(channel.part, p)
        if not channel.smooths_part():
            return value
        recent = self._recent(f"{channel.part}@smoothed")
        hit = recent.get(id(value))  # it holds `value`, whose id no other array can take meanwhile
        if hit is None or hit[0] is not value:
            hit = recent.put(id(value), (value, self.prep.kin.smooth(np.nan_to_num(value))))
        return hit[1]

    def residual(self, channel: Channel, p: dict) -> np.ndarray:
        r = self.reference(channel, p) - self.part_estimate(channel, p)
        compared = self.compared(channel)
        allowance = mean_allowance(channel, p, self.largest_current)
        if allowance > 0:
            rows = slice(None) if self.offset_rows is None else self.offset_rows
            r = _without_mean(r, r[rows] if compared is None else r[rows][compared[rows]], allowance)
        return r if compared is None else np.where(compared, r, 0.0)

    def residual_at(self, channel: Channel, p: dict, index: np.ndarray) -> np.ndarray:
        """The residual at `index` only: fits look at a sample of the training
        blocks, and the part being fitted need not be evaluated elsewhere
        (unless it is smoothed: a filter needs its neighbours)."""
        if channel.smooths_part():
            return self.residual(channel, p)[index]
        key = (id(index), self.prep.current_shift) + tuple(p.get(n, 0.0) for n in self.part_params[channel.part])
        recent = self._recent(f"{channel.part}@index")
        hit = recent.get(key)  # it holds `index`, whose id no other array can take meanwhile
        if hit is None or hit[0] is not index:
            hit = recent.put(key, (index, ESTIMATES[channel.part](self.prep, p, index)))
        r = self.reference(channel, p)[index] - hit[1]
        compared = self.compared(channel)
        compared = None if compared is None else compared[index]
        allowance = mean_allowance(channel, p, self.largest_current)
        if allowance > 0:
            if index is not self.offset_rows:
                return self.residual(channel, p)[index]
            r = _without_mean(r, r if compared is None else r[compared], allowance)
        return r if compared is None else np.where(compared, r, 0.0)




def _finite_mean(x: np.ndarray) -> float:
    x = x[np.isfinite(x)]
    return float(np.mean(x)) if len(x) else 0.0
