"""Joint torque feedback in the co-simulated system: what the estimator's
error costs the controller.

Runs the shipped SSP systems through fmpy (fmpy.ssp.simulate_ssp), 10 s at
1 kHz, in four cases:
  no JTF                 JointTorqueFeedback.ssp with controller.jtf = 0
  JTF on the UKF         JointTorqueFeedback.ssp (tau_fb <- estimator.tau_ukf)
  JTF on tau_hat         JointTorqueFeedbackHat.ssp (tau_fb <- estimator.tau_hat, the joint-state filter)
  JTF on the true torque JointTorqueFeedbackSensor.ssp (tau_fb <- joint.tau_joint)
on the nominal joint (the estimator's own parameters) and on a joint that
differs from them as real ones do (hdjoint.fmu.experiments.TRUE_JOINT_DEVIATIONS).
Prints the table (link position error, torque tracking tau_d - tau_joint,
the estimator's error) and writes docs/jtf_cosim.png.

    python benchmarks/jtf_cosim.py [--out docs/jtf_cosim.png]
"""
from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from hdjoint.fmu import cosim
from hdjoint.fmu.experiments import TRUE_JOINT_DEVIATIONS

STOP, STEP = 10.0, 1e-3
SKIP = 1.0          # s of start-up left out of the figures
LOAD = (2.0, 6.0)   # the controller's default load step (dist_on, dist_off)

CASES = (
    ("no JTF", "JointTorqueFeedback", {"controller.jtf": 0.0}),
    ("JTF on the UKF estimate", "JointTorqueFeedback", {}),
    # The default k_tau (0.15) is designed for tau_hat: a gain margin of
    # about 2 with the filter's lag and the one-step delays (docs/estimators.md).
    ("JTF on tau_hat (joint-state filter)", "JointTorqueFeedbackHat", {}),
    ("JTF on the true torque", "JointTorqueFeedbackSensor", {}),
)
# The estimate each case feeds back (its error is reported); tau_ukf otherwise.
FED_BACK = {"JointTorqueFeedbackHat": "estimator.tau_hat"}


def true_joint() -> dict[str, float]:
    from hdjoint.io import parameters
    nominal = parameters.defaults()
    return {f"joint.{k}": nominal[k] * f for k, f in TRUE_JOINT_DEVIATIONS.items()}


def metrics(r: cosim.Trajectories, estimate: str = "estimator.tau_ukf") -> dict[str, float]:
    w = r.time >= SKIP
    load = (r.time >= LOAD[0]) & (r.time < LOAD[1] + 0.5)
    e = (r["controller.theta_ref"] - r["joint.theta_l"]) * 1e3   # mrad
    trk = r["controller.tau_d"] - r["joint.tau_joint"]
    est = r[estimate] - r["joint.tau_joint"]
    rms = lambda x: float(np.sqrt(np.mean(x ** 2)))  # noqa: E731
    return {"e_rms": rms(e[w]), "e_max": float(np.abs(e[w]).max()), "e_load_max": float(np.abs(e[load]).max()),
            "trk_rms": rms(trk[w]), "trk_max": float(np.abs(trk[w]).max()),
            "est_rms": rms(est[w]), "est_max": float(np.abs(est[w]).max())}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", default="docs/jtf_cosim.png")
    args = ap.parse_args(argv)
    joints = (("nominal joint", {}), ("true joint", true_joint()))
    results = {}
    for joint_name, joint_params in joints:
        for case, system, params in CASES:
            results[(joint_name, case)] = cosim.run_fmpy(cosim.ssp_path(system), STOP, STEP,
                                                         {**joint_params, **params})
    print("| joint | case | link error RMS (mrad) | max (mrad) | max under the load step (mrad) "
          "| torque tracking RMS (N.m) | max (N.m) | estimator error RMS (N.m) |")
    print("|---|---|---|---|---|---|---|---|")
    systems = {case: system for case, system, _ in CASES}
    for (joint_name, case), r in results.items():
        m = metrics(r, FED_BACK.get(systems[case], "estimator.tau_ukf"))
        print(f"| {joint_name} | {case} | {m['e_rms']:.3f} | {m['e_max']:.3f} | {m['e_load_max']:.3f} "
              f"| {m['trk_rms']:.3f} | {m['trk_max']:.3f} | {m['est_rms']:.3f} |")

    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, axes = plt.subplots(3, 1, figsize=(9, 8), sharex=True)
    for case, _, _ in CASES:
        r = results[("true joint", case)]
        w = r.time >= 0.0
        axes[0].plot(r.time[w], 1e3 * (r["controller.theta_ref"] - r["joint.theta_l"])[w], lw=0.8, label=case)
        axes[1].plot(r.time[w], (r["controller.tau_d"] - r["joint.tau_joint"])[w], lw=0.6, label=case)
    r = results[("true joint", CASES[1][0])]
    axes[2].plot(r.time, r["joint.tau_joint"], lw=0.8, label="tau_joint (true)")
    axes[2].plot(r.time, r["estimator.tau_ukf"], lw=0.6, label="tau_ukf (estimate, JTF on it)")
    axes[2].plot(r.time, r["controller.tau_ext"], lw=1.0, label="tau_ext (load)")
    axes[0].set_ylabel("link error (mrad)")
    axes[1].set_ylabel("tau_d - tau_joint (N.m)")
    axes[2].set_ylabel("torque (N.m)")
    axes[2].set_xlabel("time (s)")
    axes[0].set_title("Joint torque feedback in co-simulation (fmpy, JointTorqueFeedback*.ssp, true joint)")
    for ax in axes:
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(args.out, dpi=110)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
