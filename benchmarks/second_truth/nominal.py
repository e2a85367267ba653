"""What the user types and what the joint really is.

The user's parameter set holds catalogue and CAD figures for a SHD-17-100-class
joint (Harmonic Drive size 17 ratio 100; a small DC motor, Kt 0.045 N.m/A;
the figures and encoder resolutions of src/hdjoint/parameter_table.def's
defaults) with the link's inertia and gravity drawn per seed (designs differ).
The truth is that set scattered within about half of each parameter's stated
tolerance (units differ from their catalogue), with a drawn encoder zero
offset a0, a drawn current-loop lag, a rigid wave generator and none of the
planted effects."""
from __future__ import annotations

USER_BASE = {
    "N": 100.0, "Kt": 0.045, "Jm": 2.09e-5, "Bm": 3.0e-5, "Fc": 0.015, "omega_fc": 1.0,
    "Kf": 1.0e4, "Cf": 0.0645, "Kw": 1.0e9, "Cw": 10.0,
    "a0": 0.0, "al1": 1.0e-4, "bl1": 0.5e-4, "omega_l": 1.0,
    "aw1": 0.6e-4, "bw1": -0.4e-4, "aw2": 0.2e-4, "bw2": 0.1e-4, "omega_w": 2.0,
    "Jl": 0.15, "Bl": 0.05, "mgl": 5.0, "motor_counts": 4096.0, "link_counts": 524288.0, "Ts": 1.0e-3,
}

# truth = user * U(lo, hi): about half the tolerances of src/hdjoint/parameter_tolerance.def
SCATTER = {"Kt": (0.97, 1.03), "Jm": (0.95, 1.05), "Bm": (0.75, 1.25), "Fc": (0.85, 1.15),
           "Kf": (0.9, 1.1), "Cf": (0.85, 1.15), "al1": (0.6, 1.4), "bl1": (0.6, 1.4),
           "aw1": (0.6, 1.4), "bw1": (0.6, 1.4), "aw2": (0.6, 1.4), "bw2": (0.6, 1.4),
           "Jl": (0.95, 1.05), "Bl": (0.75, 1.25), "mgl": (0.95, 1.05)}


def draw(rng) -> tuple[dict, dict]:
    """(truth, user) parameter sets for one seed, before any effect is planted."""
    user = dict(USER_BASE)
    user["Jl"] = round(float(rng.uniform(0.08, 0.25)), 3)
    user["mgl"] = round(float(rng.uniform(3.0, 8.0)), 2)
    truth = {k: v for k, v in user.items() if k not in ("omega_fc", "Ts")}
    for k, (lo, hi) in SCATTER.items():
        truth[k] = user[k] * float(rng.uniform(lo, hi))
    truth.update({"Kw": 0.0, "Cw": 0.0, "Fs": 0.0, "omega_s": 10.0, "backlash": 0.0, "harmonics": [],
                  "a0": float(rng.uniform(-3e-4, 3e-4)), "tau_i": float(rng.uniform(1e-4, 3e-4))})
    return truth, user
