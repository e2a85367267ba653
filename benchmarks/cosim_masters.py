"""Each master's run of JointTorqueFeedback.ssp against fmpy's: the largest
deviations, on the shipped (quantised) system and with the encoders'
quantisation off, and each master's wall time pinned to one core.

    python benchmarks/cosim_masters.py [--stop 3.0]
"""
from __future__ import annotations

import argparse
import time

import numpy as np

from hdjoint.fmu import cosim

SMOOTH = {"joint.motor_counts": 0.0, "joint.link_counts": 0.0}
LINK_COUNT = 2 * np.pi / 524288


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--stop", type=float, default=3.0)
    ap.add_argument("--cpu", type=int, default=0, help="core to pin each master to")
    args = ap.parse_args(argv)
    runs, seconds = {}, {}
    for params_name, params in (("shipped", None), ("smooth", SMOOTH)):
        for master in ("fmpy",) + cosim.MASTERS[1:]:
            t = time.perf_counter()
            runs[(params_name, master)] = cosim.run_in_subprocess(master, "JointTorqueFeedback", args.stop, 1e-3,
                                                                  cpu=args.cpu, parameters=params)
            seconds[(params_name, master)] = time.perf_counter() - t
    print(f"JointTorqueFeedback.ssp, {args.stop:g} s at 1 ms; deviations from fmpy (max |master - fmpy|):")
    print("| master | wall time, 1 core (s) | theta_l (link counts) | tau_joint max / RMS (N.m) "
          "| tau_ukf max (N.m) | i_m max (A) | theta_ref, tau_ext | quantisation off: theta_l, tau_joint, "
          "tau_ukf after 2 s |")
    print("|---|---|---|---|---|---|---|---|")
    ref, sref = runs[("shipped", "fmpy")], runs[("smooth", "fmpy")]
    late = sref.time > 2.0
    for master in ("fmpy",) + cosim.MASTERS[1:]:
        r, s = runs[("shipped", master)], runs[("smooth", master)]
        d = {k: np.abs(r[k] - ref[k]) for k in cosim.SIGNALS}
        ds = {k: np.abs(s[k] - sref[k])[late].max() for k in cosim.SIGNALS}
        exact = all(np.array_equal(r[k], ref[k]) for k in ("controller.theta_ref", "controller.tau_ext"))
        print(f"| {master} | {seconds[('shipped', master)]:.1f} | {d['joint.theta_l'].max() / LINK_COUNT:.1f} "
              f"| {d['joint.tau_joint'].max():.3f} / {np.sqrt(np.mean(d['joint.tau_joint'] ** 2)):.3f} "
              f"| {d['estimator.tau_ukf'].max():.3f} | {d['controller.i_m'].max():.3f} "
              f"| {'identical' if exact else 'DIFFER'} "
              f"| {ds['joint.theta_l']:.1e} rad, {ds['joint.tau_joint']:.1e} N.m, {ds['estimator.tau_ukf']:.1e} N.m |")
    base = runs[("shipped", "libcosim-ssp")]
    print("\nlargest deviation between the external masters (vs libcosim-ssp), over all signals:")
    for master in cosim.MASTERS[2:]:
        r = runs[("shipped", master)]
        worst = max(cosim.SIGNALS, key=lambda k: np.abs(r[k] - base[k]).max())
        print(f"  {master}: {np.abs(r[worst] - base[worst]).max():.2e} ({worst})")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
