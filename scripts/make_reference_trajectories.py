"""Regenerate the committed reference trajectories tests/data/<FMU>_in.csv and
<FMU>_ref.csv (inputs, and the outputs fmpy's simulate_fmu records), as the
Reference-FMUs ship theirs. Run after a deliberate change of the model:
    python scripts/make_reference_trajectories.py
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
from fmpy import simulate_fmu

from hdjoint.fmu import experiments
from hdjoint.fmu.shipped import fmu_path
from hdjoint.io.recording import write_csv

DATA = Path(__file__).resolve().parent.parent / "tests" / "data"
STEP = 1e-3


def joint_inputs():
    # 2 s: a current ramp and sine lifting the link, and an external load step.
    t = np.round(np.arange(0.0, 2.0 + STEP / 2, STEP), 9)
    i_m = 0.6 * np.minimum(t / 0.5, 1.0) + 0.3 * np.sin(2 * np.pi * 1.5 * t)
    tau_ext = np.where(t >= 1.0, 1.5, 0.0) * np.minimum(np.maximum((t - 1.0) / 0.05, 0.0), 1.0)
    return {"time": t, "i_m": i_m, "tau_ext": tau_ext}


def estimator_inputs():
    rec = experiments.run("paper", duration=3.0)
    return {"time": np.round(rec.time, 9), "i_m": rec.i_m, "theta_m": rec.theta_m, "theta_l": rec.theta_l}


def simulate(name: str, inputs: dict, outputs: list[str]) -> dict:
    signal = np.array(list(zip(*inputs.values())), dtype=[(k, float) for k in inputs])
    result = simulate_fmu(str(fmu_path(name)), stop_time=float(inputs["time"][-1]), step_size=STEP,
                          output_interval=STEP, input=signal, output=outputs)
    return {"time": result["time"], **{k: result[k] for k in outputs}}


def main():
    DATA.mkdir(parents=True, exist_ok=True)
    cases = {
        "HarmonicDriveJoint": (joint_inputs(), ["theta_m", "theta_l", "tau_joint", "omega_m", "omega_link"]),
        "JointTorqueEstimator": (estimator_inputs(),
                                 ["tau_ukf", "tau_compliance", "omega_m", "dtheta_f", "tau_ukf_std", "tau_hat",
                                  "tau_hat_std"]),
    }
    for name, (inputs, outputs) in cases.items():
        write_csv(DATA / f"{name}_in.csv", inputs)
        write_csv(DATA / f"{name}_ref.csv", simulate(name, inputs, outputs))
        print(f"wrote {DATA / name}_in.csv and _ref.csv")


if __name__ == "__main__":
    main()
