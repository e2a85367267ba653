"""From the joint to a contract CSV: run the integrator with the probes the
sensor forms ask for, then pass the readings through the forms (current
sensor, encoders, torque sensor, time stamps, dropped rows), in that order."""
from __future__ import annotations

import csv
from pathlib import Path

import numpy as np

from . import simulate

ORDER = ("current_sensor", "encoder", "torque_sensor", "timing", "dropouts")


def record(joint, controller, duration: float, Ts: float, sensors: list, rng, counts: dict) -> dict:
    """Simulate and read the joint as its sensors would; returns the channels
    (`time`, `i_m`, `theta_m`, `theta_l`, `tau_sensor`, `keep`) and the truth at the ticks."""
    ticks = np.arange(int(round(duration / Ts)) + 1) * Ts
    by_role = {f.role: f for f in sensors}
    cur = by_role["current_sensor"]
    t_cur = cur.probe_times(ticks)
    order = np.argsort(t_cur, kind="stable")
    timing = by_role.get("timing")
    t_enc = timing.read_times(ticks, rng) if hasattr(timing, "read_times") else ticks
    sim = simulate.run(joint, controller, duration, Ts, {"cur": t_cur[order], "enc": t_enc})
    N = joint.p["N"]
    i_nodes = np.empty(len(t_cur))
    i_nodes[order] = sim["probes"]["cur"][:, 4]
    enc = sim["probes"]["enc"]
    tau_true = np.array([joint.tau_f(t, y) for t, y in zip(ticks, sim["states"])])
    rec = {"ticks": ticks, "time": ticks.copy(), "i_nodes": i_nodes, "counts": counts,
           "theta_m_true": N * (enc[:, 0] + enc[:, 2]), "theta_l_true": enc[:, 0].copy(),
           "tau_true": tau_true, "keep": np.ones(len(ticks), bool), "dropped": 0, "sim": sim}
    for role in ORDER:
        if role in by_role:
            by_role[role].apply(rec, rng)
    return rec


def write_csv(path: Path, rec: dict, with_sensor: bool) -> None:
    """The contract's recording: time,i_m,theta_m,theta_l[,tau_sensor], SI, rows kept only."""
    cols = ["time", "i_m", "theta_m", "theta_l"] + (["tau_sensor"] if with_sensor else [])
    keep = rec["keep"]
    data = np.column_stack([np.asarray(rec[c])[keep] for c in cols])
    if not np.all(np.diff(data[:, 0]) > 0):
        raise ValueError("time column not strictly increasing")
    with open(path, "w", newline="") as fh:
        w = csv.writer(fh)
        w.writerow(cols)
        for row in data:
            w.writerow([repr(float(v)) for v in row])
