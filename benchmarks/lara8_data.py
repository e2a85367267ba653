"""The LARA8 recordings' conventions (../shared/data/lara8, see its README),
shared by the LARA8 benchmarks and tests: where the files are, the current's
sign and the gears' tooth ratios, the catalogue stiffness of a size-25 gear,
the nominal set per joint, and the tables' stamp."""
from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import stamp
from hdjoint.diagnosis.model.kinematics import kinematics
from hdjoint.io import parameters
from hdjoint.io.recording import read_recording
from scipy.optimize import minimize_scalar

ROOT = Path(__file__).resolve().parents[1]
# ../shared/data/lara8 beside the main checkout (a worktree sits one level deeper); the copy the
# tests carry (tests/data/lara8, the same files) where that is absent (CI).
DATA = next((d for d in (ROOT.parent / "shared/data/lara8", ROOT.parent.parent / "shared/data/lara8") if d.is_dir()),
            ROOT / "tests/data/lara8")
TABLE = ROOT / "docs" / "results" / "lara8.md"
KT = 0.1                          # N.m/A, the README's convention for these files
K1, K2, K3, T1, T2 = 31000.0, 50000.0, 57000.0, 14.0, 48.0  # catalogue, size-25 gear (thesis)
T_MAX = 160.0  # N.m, the largest torque these recordings carry (joint 2, 98th percentile)
# The gears' exact ratios (whole numbers of teeth: circular-spline output of a 120:1 / 100:1 flexspline
# runs at 121:1 / 101:1; examples/lara8/README.md). The encoders' least-squares slope differs from them
# by up to 0.14 % because it also absorbs whatever torsion drifts with the link angle (gravity, link-order
# kinematic error): fitting N to the encoders hides that torsion from the diagnosis.
TOOTH_RATIO = {"joint1": 121, "joint2": 121, "joint3": 101}
# The files' current has the robot's joint-torque sign, their encoders their own counting direction:
# the source log's link encoders of joints 1 and 2 count against the robot's joint angle (-2^24/(2 pi)
# counts per rad of `joint_angles_k`), joint 3's with it. CONTRACT.md wants positive torque to drive
# the encoders positive, so joints 1 and 2 are read with i_m negated (docs/diagnosis_lara8.md, "What the recordings are made of":
# the motor inertia comes out negative otherwise).
CURRENT_SIGN = {"joint1": -1.0, "joint2": -1.0, "joint3": 1.0}
JOINTS = {"joint1": ["joint1_jog.csv", "joint1_jog_linear_mass.csv"], "joint2": ["joint2_jog_joint_mass.csv"],
          "joint3": ["joint3_jog_linear_mass.csv"]}


def catalogue_torsion(tau: np.ndarray) -> np.ndarray:
    """The catalogue's piecewise-linear torsion curve (K1 to T1, K2 to T2, K3 beyond), rad."""
    t = np.abs(tau)
    return np.where(t < T1, t / K1, np.where(t < T2, T1 / K1 + (t - T1) / K2, T1 / K1 + (T2 - T1) / K2 + (t - T2) / K3))


def catalogue_cf() -> float:
    """Cf of eq. (5) (Kf = K1) fitted by least squares to the catalogue's curve up to T_MAX.
    Matched at T2 alone (Cf = 0.025), the atan law saturates: eq. (8)'s pole (2.0e-3 rad) lies
    below the catalogue's torsion at 110 N.m, and joints 2 and 3 carry 80-160 N.m, where a
    torsion change of 4e-5 rad (the kinematic error) then reads as 15 N.m or more."""
    tau = np.linspace(0.0, T_MAX, 200)
    return float(minimize_scalar(lambda cf: np.sum((np.arctan(cf * tau) / (cf * K1) - catalogue_torsion(tau)) ** 2),
                                 bounds=(1e-5, 0.1), method="bounded").x)


def read_joint(path: Path):
    """A LARA8 recording with its current in the encoders' sense (CURRENT_SIGN)."""
    rec = read_recording(path)
    return dataclasses.replace(rec, i_m=CURRENT_SIGN[path.name.split("_")[0]] * rec.i_m)


def gear_ratio(rec) -> float:
    return float(np.polyfit(rec.theta_l, rec.theta_m, 1)[0])


def _reversals(x, threshold) -> int:
    s = np.sign(x[np.abs(x) > threshold])
    return int(np.count_nonzero(np.diff(s)))


def contents(rec, n: float, doc: dict) -> dict:
    """What the recording holds, and what it therefore cannot say: the
    diagnosis's own reasons (`not_testable`), grouped by reason, so that the
    table and the engine cannot disagree. (A list written here said
    "friction and hysteresis are not testable" on joint1_jog, whose load
    reverses, while the engine tested hysteresis there.)"""
    kin = kinematics(rec, sigma_s=0.02)
    torque = rec.i_m * n * KT
    info = {"duration_s": round(rec.duration, 2), "samples": len(rec),
            "median_step_ms": round(1e3 * float(np.median(np.diff(rec.time))), 2),
            "motor_revolutions": round(float(np.ptp(rec.theta_m)) / (2 * math.pi), 2),
            "link_travel_rad": round(float(np.ptp(rec.theta_l)), 3),
            "motor_reversals": _reversals(kin.omega_m, 0.5), "link_reversals": _reversals(kin.omega_l, 0.005),
            "torque_range_Nm": [round(float(np.percentile(torque, 2)), 1), round(float(np.percentile(torque, 98)), 1)]}
    by_reason: dict[str, list[str]] = {}
    for entry in doc.get("not_testable", []):
        reason = entry["reason"].removeprefix("not testable on this recording: ")
        by_reason.setdefault(reason, []).append(entry["effect"])
    info["cannot_say"] = [f"{reason}: {', '.join(effects)} not testable" for reason, effects in by_reason.items()]
    return info


def nominal_for(n: float) -> dict:
    return dict(parameters.defaults(), N=n, Kt=KT, Kf=K1, Cf=catalogue_cf(), mgl=0.0)


def calibrated_set(nominal: dict, calibration: dict) -> dict:
    return dict(nominal, **{k: calibrated_value(v) for k, v in calibration.items()})


def halves(rec):
    mid = len(rec) // 2
    return rec.slice(0, mid), rec.slice(mid, None)


# The parameter files examples/lara8 ships, per joint (no kinematic-error model: eq. (7) all zero; a0 the
# joint's encoder zero), which its README's commands and the README's LARA8 table use.
EXAMPLES = {joint: ROOT / "examples/lara8" / f"{joint}_params.json" for joint in JOINTS}

def generated_by(script: str) -> str:
    """The stamp every LARA8 table opens with: what wrote it, when, at which commit, on which machine."""
    return stamp.generated_by(f"python benchmarks/{script}")


def markdown_table(header: list[str], cells: list[list]) -> list[str]:
    """The lines of a Markdown table."""
    return ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)] + \
        ["| " + " | ".join(str(c) for c in row) + " |" for row in cells]


def calibrated_value(entry: dict):
    """The calibrated value of a calibration entry, in either schema (today's or issue 10's)."""
    return entry.get("estimate", entry.get("calibrated"))
