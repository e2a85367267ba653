"""The first stage: recordings made ready for the diagnosis. The checks a
recording must pass, several recordings of one joint joined, the folds and
the fit sample, the residual channels, each encoder zero placed, and the
eq. (7) kinematic-error terms a parameter set has."""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, field
from typing import Callable

import numpy as np

from hdjoint.diagnosis.model.residual_channels import Channel, Evaluator, channels_for
from hdjoint.diagnosis.model.kinematics import folds as make_folds
from hdjoint.diagnosis.model.kinematics import kinematics
from hdjoint.diagnosis.model.torque_estimates import Prepared
from hdjoint.diagnosis.model.kinematics import sample_windows, window_labels
from hdjoint.diagnosis.rules import ANALYSED_SECONDS, FIT_SAMPLES, FOLDS, MIN_DURATION, MIN_SAMPLES
from hdjoint.diagnosis.model.structure import RESOLVING_PERIODS, resolves
from hdjoint.io import parameters
from hdjoint.io.recording import Recording
from hdjoint.io.timebase import GAP_FACTOR


class DiagnosisError(ValueError):
    """The recording cannot be diagnosed (too short, gaps, ...)."""



def check_recording(rec: Recording) -> None:
    where = rec.path or "recording"
    if len(rec) < MIN_SAMPLES or rec.duration < MIN_DURATION:
        raise DiagnosisError(f"{where}: too short to diagnose ({len(rec)} samples, {rec.duration:.2f} s; "
                             f"need at least {MIN_SAMPLES} samples and {MIN_DURATION} s)")
    dt = np.diff(rec.time)
    step = float(np.median(dt))
    gaps = np.flatnonzero(dt > GAP_FACTOR * step)  # the same rule as `hdjoint estimate`'s
    if len(gaps):
        g = gaps[0]
        raise DiagnosisError(f"{where}: a gap of {dt[g]:.4g} s after t = {rec.time[g]:.6g} s (line {g + 2}); "
                             f"the median step is {step:.4g} s. Split the recording at its gaps.")



def eq7_terms(p: dict) -> dict[str, tuple[tuple[float, tuple[str, str]], ...]]:
    """eq. (7)'s harmonics: per angle, (order, its cosine and sine coefficients' names)."""
    return {"theta_m": ((p["omega_w"], ("aw1", "bw1")), (2 * p["omega_w"], ("aw2", "bw2"))),
            "theta_l": ((p["omega_l"], ("al1", "bl1")),)}


def eq7_orders(p: dict) -> dict[str, tuple[float, ...]]:
    """The angle orders eq. (7) already models in `p`: only those whose
    coefficients are nonzero. A nominal set without a kinematic-error model
    (all zero, as a catalogue gives no phase) must leave them to the order
    search, or the wave generator's two-lobe error can never be found."""
    return {angle: tuple(order for order, names in pairs if any(p.get(n, 0.0) for n in names))
            for angle, pairs in eq7_terms(p).items()}


def unresolved_harmonics(rec: Recording, p: dict) -> dict[str, str]:
    """eq. (7) coefficients whose harmonic the recording's travel does not
    resolve (structure.resolves), each with why. Over a fraction of a
    period a harmonic's cosine and sine are two smooth curves that take
    whatever else changes along the travel (a hysteresis loop, say), and
    move far from nominal with held-out support."""
    out = {}
    for angle, terms in eq7_terms(p).items():
        travel = float(np.ptp(getattr(rec, angle)))
        for order, names in terms:
            if not resolves(order, travel):
                why = (f"{angle} travels {travel:.3g} rad ({travel / (2 * math.pi):.2g} revolution), under the "
                       f"{RESOLVING_PERIODS:g} periods its order {order:g} needs to be told from anything else "
                       "that changes along the travel")
                out.update({n: why for n in names})
    return out


# The encoder zero: a property of each recording, placed on it (place_offset), never carried from another.
ENCODER_ZERO = "a0"


def place_offset(rec: Recording, p: dict, reference_torque: np.ndarray) -> dict:
    """`p` with a0 placed so the transmission's median torsion on `rec` matches
    the reference torque's: encoder zeros are arbitrary per recording (power
    cycles, multi-turn counts), and a0 from another recording can put the
    torsion past eq. (8)'s pole, where every residual is NaN."""
    from hdjoint import _core
    est = _core.compliance(parameters.for_estimator(p), rec.i_m, rec.theta_m, rec.theta_l)
    cf, kf = p["Cf"], p["Kf"]
    ref_torsion = np.arctan(cf * reference_torque) / (cf * kf) if cf > 1e-12 else reference_torque / kf
    shift = float(np.nanmedian(est["dtheta_f"] - ref_torsion))
    return dict(p, **{ENCODER_ZERO: p[ENCODER_ZERO] + shift})


def joined(recordings: list[Recording]) -> tuple[Recording, np.ndarray, np.ndarray, np.ndarray]:
    """Several recordings of one joint as one analysed recording: each one's
    analysed windows, one after the other on a continuous time axis. Returns
    it, the first sample of each contiguous window, each sample's time since
    its own recording's start, and the fold labels (even fit, odd held out)."""
    if len({r.tau_sensor is None for r in recordings}) > 1:
        raise DiagnosisError("the recordings must all have a torque sensor column or none of them")
    pieces, starts, t_rel, fold = [], [], [], []
    offset, label = 0, 0
    for rec in recordings:
        part, part_starts = sample_windows(rec, ANALYSED_SECONDS / len(recordings), FOLDS)
        labels = make_folds(len(part), FOLDS) if len(part_starts) == 1 else window_labels(len(part), part_starts)
        pieces.append(part)
        starts += list(part_starts + offset)
        t_rel.append(part.time - rec.time[0])
        fold.append(labels + label)
        offset += len(part)
        label += int(labels.max()) + 1 + int(labels.max() + 1) % 2  # keep even = fit in every recording
    if len(pieces) == 1:
        return pieces[0], np.array(starts), t_rel[0], fold[0]
    step = float(np.median(np.diff(pieces[0].time)))
    times, end = [], 0.0
    for part in pieces:
        times.append(part.time - part.time[0] + end)
        end = times[-1][-1] + step

    def cat(name):
        arrays = [getattr(r, name) for r in pieces]
        return None if arrays[0] is None else np.concatenate(arrays)

    rec = Recording(time=np.concatenate(times), i_m=cat("i_m"), theta_m=cat("theta_m"), theta_l=cat("theta_l"),
                    tau_sensor=cat("tau_sensor"), extra={}, path=" + ".join(str(r.path) for r in recordings))
    return rec, np.array(starts), np.concatenate(t_rel), np.concatenate(fold)


# Parts with no model term for a constant torque: the current sensor's offset
# (N*Kt*i_0) and the torque sensor's reach them as a constant that no
# parameter can take (the transmission's a0 takes it there), and a few
# hundredths of an ampere of it, traded against Kt, read as structure
# against the torque level. Their channels against the torque sensor are
# compared free of their mean over the fit rows (profiled out, like a
# fitted offset).


@dataclass(frozen=True)
class Setup:
    """One or several recordings of a joint, ready to be diagnosed against a
    nominal set: what every later stage reads. The folds alternate: even ones
    fit, odd ones are held out; samples where the smoothing filter runs off a
    window's ends take no part."""
    recordings: list[Recording]
    source: Recording            # the first recording whole; `rec` is what is analysed
    rec: Recording
    fold: np.ndarray
    prep: Prepared
    channels: list[Channel]
    eval: Evaluator
    train: np.ndarray
    test: np.ndarray
    used: np.ndarray
    stride: int                  # training samples per fit sample
    fit_index: np.ndarray
    nominal: dict
    tolerance: dict
    say: Callable[[str], None] = field(repr=False, default=lambda message: None)
    workers: int | None = None   # processes that fit a round's hypotheses (None: one per core)
    started: float = 0.0

    @property
    def has_sensor(self) -> bool:
        return self.rec.tau_sensor is not None

    def channels_of(self, part: str) -> list[Channel]:
        return [c for c in self.channels if part in c.parts()]


def prepare(rec: Recording | list[Recording], nominal: dict[str, float], tolerance: dict[str, float] | None = None,
            progress: Callable[[str], None] | None = None, workers: int | None = None) -> Setup:
    """Check and join the recordings, and lay out the folds, the fit sample and the residual channels."""
    started = time.perf_counter()
    recordings = list(rec) if isinstance(rec, (list, tuple)) else [rec]
    for r in recordings:
        check_recording(r)
    say = progress or (lambda message: None)
    whole, starts, t_rel, fold = joined(recordings)
    if len(starts) > len(recordings):
        say(f"analysing {len(starts)} windows spread over the recordings, {ANALYSED_SECONDS:.0f} s in all")
    prep = Prepared(whole, kinematics(whole, starts=starts), t_rel, starts)
    channels = channels_for(whole.tau_sensor is not None)
    evaluator = Evaluator(prep, channels)
    train = (fold % 2 == 0) & prep.kin.valid
    test = (fold % 2 == 1) & prep.kin.valid
    stride = max(1, int(np.count_nonzero(train) // FIT_SAMPLES))
    fit_index = np.flatnonzero(train)[::stride]
    evaluator.offset_rows = fit_index
    return Setup(recordings, recordings[0], whole, fold, prep, channels, evaluator, train, test, train | test, stride,
                 fit_index, dict(nominal), dict(tolerance or {}), say, workers, started)
