"""What the LARA8 recordings' torsion is made of, before any model is fitted.

For each recording of ../shared/data/lara8 (see its README): the torsion
theta_m/N - theta_l (N the gear's tooth ratio, 121 or 101), its size against
what the reported torque Kt*N*i_m would twist a catalogue flexspline by
(K1 = 31000 N.m/rad), one least-squares description of it

    torsion = c + torsion-per-torque * tau + link-angle polynomial (degree 2)
              + sum over motor orders k of (a_k cos k theta_m + b_k sin k theta_m)

(each coefficient with a 95 % interval whose standard error is inflated by
the residual's correlation length), the share of the torsion variance each
group explains on its own, and what the reported torque itself is made of:

    tau = c + Coulomb * sign(omega_m) + viscous * omega_l + inertia * alpha_m + gravity terms in theta_l.

Run: python benchmarks/lara8_torsion.py [--data DIR] -> docs/results/lara8_torsion.md
"""
from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from scipy.stats import norm

sys.path.insert(0, str(Path(__file__).resolve().parent))
from lara8_data import CURRENT_SIGN, DATA, K1, KT, TOOTH_RATIO, gear_ratio, generated_by, \
    markdown_table  # noqa: E402

from hdjoint.io import parameters  # noqa: E402
from hdjoint.io.recording import read_recording  # noqa: E402
from hdjoint.diagnosis.model.kinematics import kinematics  # noqa: E402
from hdjoint.diagnosis.search.torsion_orders import correlation_length  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TABLE = ROOT / "docs" / "results" / "lara8_torsion.md"
MOTOR_ORDERS = (1, 2, 4, 6)  # the wave generator's two lobes make 2 (and its harmonics) the expected ones


def regress(columns: dict[str, np.ndarray], y: np.ndarray) -> tuple[dict, np.ndarray, int]:
    """Least squares; each coefficient with its 95 % half-width (OLS standard
    error times sqrt(correlation length): neighbouring samples are not independent)."""
    names = list(columns)
    x = np.column_stack([columns[n] for n in names])
    coef, *_ = np.linalg.lstsq(x, y, rcond=None)
    residual = y - x @ coef
    length = correlation_length(residual)
    dof = max(len(y) - len(names), 1)
    cov = np.linalg.pinv(x.T @ x) * float(residual @ residual) / dof * length
    half = norm.ppf(0.975) * np.sqrt(np.clip(np.diag(cov), 0.0, None))
    return {n: (float(c), float(h)) for n, c, h in zip(names, coef, half)}, residual, length


def share(columns: dict[str, np.ndarray], y: np.ndarray) -> float:
    """Variance share of y explained by `columns` (plus a constant) on their own."""
    _, residual, _ = regress({"1": np.ones_like(y), **columns}, y)
    return float(1.0 - residual.var() / y.var())


def motor_harmonics(theta_m: np.ndarray) -> dict[str, np.ndarray]:
    return {f"{f}{k}": g(k * theta_m) for k in MOTOR_ORDERS for f, g in (("cos", np.cos), ("sin", np.sin))}


def amplitude(coef: dict, k: int) -> tuple[float, float]:
    """Amplitude of motor order k and its half-width (delta method, the larger of the two parts' widths)."""
    (a, ha), (b, hb) = coef[f"cos{k}"], coef[f"sin{k}"]
    return math.hypot(a, b), max(ha, hb)


def anatomy(name: str, rec) -> dict:
    joint = name.split("_")[0]
    n = TOOTH_RATIO[joint]
    kin = kinematics(rec, sigma_s=0.02)
    ok = kin.valid
    logged = (KT * n * rec.i_m)[ok]
    torque = CURRENT_SIGN[joint] * KT * n * rec.i_m
    torsion = rec.theta_m / n - rec.theta_l
    torsion = (torsion - torsion.mean())[ok]
    tau, tm = torque[ok], rec.theta_m[ok]
    tl = rec.theta_l[ok] - rec.theta_l[ok].mean()
    link = {"theta_l": tl, "theta_l^2": tl ** 2}
    coef, residual, length = regress({"1": np.ones_like(tau), "tau": tau, **link, **motor_harmonics(tm)}, torsion)
    omega, alpha = kin.omega_m[ok], kin.alpha_m[ok]
    parts, _, _ = regress({"1": np.ones_like(tau), "sign(omega_m)": np.sign(omega), "omega_l": omega / n,
                           "alpha_m": alpha, "sin(theta_l)": np.sin(rec.theta_l[ok]),
                           "cos(theta_l)": np.cos(rec.theta_l[ok])}, logged)
    dt = np.diff(rec.time)
    nominal = parameters.defaults()
    eq7 = {1: 0.0, 2: math.hypot(nominal["aw1"], nominal["bw1"]), 4: math.hypot(nominal["aw2"], nominal["bw2"])}
    return {
        "recording": name, "N": n, "N_encoders": gear_ratio(rec),
        "step_ms": (1e3 * float(np.median(dt)), 1e3 * float(np.std(dt)), 1e3 * float(dt.max())),
        "torsion_std": float(torsion.std()), "torsion_ptp": float(np.ptp(torsion)),
        "torque_pct": (float(np.percentile(tau, 2)), float(np.percentile(tau, 98))),
        "torque_torsion_K1": float(np.std(tau) / K1),
        "per_torque": coef["tau"],
        "shares": {"torque": share({"tau": tau}, torsion), "link angle (quadratic)": share(link, torsion),
                   "motor orders": share(motor_harmonics(tm), torsion)},
        "all_explained": float(1.0 - residual.var() / torsion.var()), "residual_std": float(residual.std()),
        "correlation_samples": length,
        "orders": {k: amplitude(coef, k) for k in MOTOR_ORDERS}, "eq7": eq7,
        "motor_revolutions": float(np.ptp(rec.theta_m)) / (2 * math.pi),
        "torque_parts": parts, "torque_share_motor_side": share({"s": np.sign(omega), "w": omega / n, "a": alpha}, logged),
        "current_sign": CURRENT_SIGN[joint],
    }


def _pm(value: tuple[float, float], fmt: str) -> str:
    return f"{value[0]:{fmt}} ± {value[1]:{fmt}}"


def write_table(rows: list[dict], path: Path = TABLE) -> str:
    lines = ["# What the LARA8 torsion is made of", "", generated_by("lara8_torsion.py"),
             "Torsion = theta_m/N - theta_l with N the tooth ratio (121 joints 1-2, 101 joint 3), mean removed; "
             f"torque = Kt*N*i_m with Kt = {KT}, its sign turned to the encoders' (negated for joints 1 and 2, "
             "lara8_table.CURRENT_SIGN) except in the last table, which shows it as logged. Intervals: 95 %, "
             "OLS standard errors times sqrt(the residual's correlation length in samples). "
             "Eq. (7) nominal: the contract defaults (orders 2 and 4 of theta_m).", "",
             "## Torsion against torque", ""]
    lines += markdown_table(
        ["recording", "step ms (median / std / max)", "N (teeth / encoders' slope)", "torque 2-98 % (N.m)",
         "torsion std (rad)", "torque's torsion at K1 (std, rad)", "torsion per torque (rad/N.m; 1/K1 = 3.2e-5)",
         "variance share: torque / link angle / motor orders / all", "residual std (rad)"],
        [[r["recording"], "{:.1f} / {:.2f} / {:.1f}".format(*r["step_ms"]), f"{r['N']} / {r['N_encoders']:.3f}",
          "{:.0f} .. {:.0f}".format(*r["torque_pct"]), f"{r['torsion_std']:.2e}", f"{r['torque_torsion_K1']:.2e}",
          _pm(r["per_torque"], ".1e"), " / ".join(f"{v:.2f}" for v in (*r["shares"].values(), r["all_explained"])),
          f"{r['residual_std']:.1e}"] for r in rows])
    lines += ["", "## The motor-angle-periodic torsion (kinematic error), amplitude per order (rad)", ""]
    lines += markdown_table(
        ["recording", "motor rev"] + [f"order {k} (eq. (7) nominal)" for k in MOTOR_ORDERS],
        [[r["recording"], f"{r['motor_revolutions']:.1f}"] +
         [f"{_pm(r['orders'][k], '.1e')} ({r['eq7'].get(k, 0.0):.1e})" for k in MOTOR_ORDERS] for r in rows])
    lines += ["", "## What the reported torque is made of, as logged (N.m)", ""]
    lines += markdown_table(
        ["recording", "Coulomb (x sign omega_m)", "viscous (per rad/s of link)", "motor inertia (per rad/s^2 of motor)",
         "sin / cos theta_l", "variance share of the motor-side terms"],
        [[r["recording"], _pm(r["torque_parts"]["sign(omega_m)"], ".1f"), _pm(r["torque_parts"]["omega_l"], ".0f"),
          _pm(r["torque_parts"]["alpha_m"], ".3f"),
          f"{_pm(r['torque_parts']['sin(theta_l)'], '.0f')} / {_pm(r['torque_parts']['cos(theta_l)'], '.0f')}",
          f"{r['torque_share_motor_side']:.2f}"] for r in rows])
    text = "\n".join(lines) + "\n"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text)
    return text


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", type=Path, default=DATA, help="folder of the LARA8 recordings")
    args = ap.parse_args()
    files = sorted(p.name for p in args.data.glob("joint*.csv"))
    print(write_table([anatomy(f, read_recording(args.data / f)) for f in files]))


if __name__ == "__main__":
    main()
