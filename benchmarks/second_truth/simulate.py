"""The integrator: scipy's solve_ivp (LSODA: it switches to BDF when the
friction forms' presliding makes the ODE stiff) over each sample period, the
drive's command held over it (zero-order hold), max_step = Ts. Each period's
dense output answers the probes that fall inside it: readings taken at other
instants than the sample ticks (jittered encoders, a delayed or lagging
current sensor). A probe before t = 0 reads the rest state (the joint starts
at rest in static equilibrium)."""
from __future__ import annotations

import numpy as np
from scipy.integrate import solve_ivp


def run(joint, controller, duration: float, Ts: float, probes: dict | None = None,
        tau_ext=None, rtol: float = 1e-6, method: str = "LSODA") -> dict:
    """Simulate; return ticks, the states and commands at the ticks, and each
    probe's states (rows in the order of its times, which must be sorted)."""
    probes = probes or {}
    n = int(round(duration / Ts)) + 1
    ticks = np.arange(n) * Ts
    y, _ = joint.rest_state(controller.start_angle(), 0.0 if tau_ext is None else float(tau_ext[0]))
    atol = joint.atol()
    N = joint.p["N"]
    out = {k: np.full((len(v), joint.n), np.nan) for k, v in probes.items()}
    for k, v in probes.items():
        out[k][v <= 0.0] = y
    states = np.empty((n, joint.n))
    cmds = np.empty(n)
    for k in range(n):
        t = ticks[k]
        states[k] = y
        u = controller.command(k, N * (y[0] + y[2]))
        cmds[k] = u
        if k == n - 1:
            break
        te = 0.0 if tau_ext is None else float(tau_ext[k])
        t1 = ticks[k + 1]  # not t + Ts: a probe on the next tick must fall in this period
        sol = solve_ivp(joint.rhs, (t, t1), y, method=method, args=(u, te), max_step=Ts,
                        rtol=rtol, atol=atol, dense_output=bool(probes))
        if not sol.success:
            raise RuntimeError(f"integration failed at t={t}: {sol.message}")
        for name, times in probes.items():
            lo, hi = np.searchsorted(times, [max(t, 0.0), t1], side="right")
            if hi > lo:
                out[name][lo:hi] = sol.sol(times[lo:hi]).T
        y = sol.y[:, -1].copy()
    for name, v in out.items():
        late = v[:, 0] != v[:, 0]
        if late.any():  # only probes after the last tick may be left
            if np.any(probes[name][late] <= ticks[-1]):
                raise RuntimeError(f"probe {name} not filled")
            v[late] = y
    return {"ticks": ticks, "states": states, "i_cmd": cmds, "probes": out}
