"""The open-library fallback: when structure remains in a residual that no
named effect explains, propose a term for it by sparse regression over a
library of candidate features, judged on data it was not fitted on.

The library, built from the prepared recording (signals.py kinematics):
harmonics of both angles; speed, acceleration and torque polynomials; sign
and absolute-value terms; lagged current; and products of these that the
named effects do not cover, e.g. position-dependent friction
sign(omega_m)*cos(k*theta_m) or a kinematic error modulated by torque
tau*cos(k*theta_m). Channels that see the world through the kinematics'
smoothing filter see each feature through it too.

The fit is scikit-learn's orthogonal matching pursuit on the training
folds (orthogonal_mp_gram, the whole path at once); the number of terms is the one with the best held-out error on the
other folds, and the proposal reports that held-out gain (with the fold z
of structure.held_out_gain_sq). A proposal is a description for a person
to read, not a finding: it changes no verdict and no parameter."""
from __future__ import annotations

import numpy as np

from hdjoint.diagnosis.rules import EVIDENCE_Z, PROPOSAL_MIN_GAIN
from hdjoint.diagnosis.model.structure import held_out_gain_sq

MAX_TERMS = 4
SAMPLES = 6000         # training samples the regression sees (and as many held out)
SMOOTH_SPEED = 0.5     # rad/s of the motor over which sign() is smoothed (tanh)
SMOOTH_LINK_SPEED = 0.005  # rad/s of the link, the same


def _harmonic_orders(travel: float, orders) -> list[float]:
    """Orders whose period the recording covers at least once."""
    return [k for k in orders if k * travel >= 2 * np.pi]


def features(rec, kin, torque: np.ndarray) -> dict[str, np.ndarray]:
    """The candidate library, name -> column over the whole recording."""
    wm, am, wl = kin.omega_m, kin.alpha_m, kin.omega_l
    scale_w = max(np.percentile(np.abs(wm), 95), 1e-9)
    sign_m = np.tanh(wm / SMOOTH_SPEED)
    sign_l = np.tanh(wl / SMOOTH_LINK_SPEED)
    lib = {
        "omega_m": wm, "omega_m^2*sign(omega_m)": wm * np.abs(wm) / scale_w, "omega_m^3": wm ** 3 / scale_w ** 2,
        "alpha_m": am, "omega_l": wl, "sign(omega_m)": sign_m, "sign(omega_l)": sign_l, "|omega_m|": np.abs(wm),
        "tau": torque, "tau^2": torque ** 2, "tau^3": torque ** 3, "|tau|": np.abs(torque),
        "sign(omega_m)*|tau|": sign_m * np.abs(torque), "t*sign(omega_m)": (rec.time - rec.time[0]) * sign_m,
    }
    for lag in (1, 2, 5, 10):
        lagged = np.concatenate([np.full(lag, rec.i_m[0]), rec.i_m[:-lag]])
        lib[f"i_m[t-{lag}]-i_m"] = lagged - rec.i_m
    angles = {"theta_m": (rec.theta_m, _harmonic_orders(np.ptp(rec.theta_m), [k / 2 for k in range(1, 17)])),
              "theta_l": (rec.theta_l, _harmonic_orders(np.ptp(rec.theta_l), range(1, 9)))}
    for name, (angle, orders) in angles.items():
        for k in orders:
            for trig, f in (("cos", np.cos), ("sin", np.sin)):
                h = f(k * angle)
                term = f"{trig}({k:g}*{name})"
                lib[term] = h
                lib[f"sign(omega_m)*{term}"] = sign_m * h
                lib[f"tau*{term}"] = torque * h
    return lib


def _sampled(mask: np.ndarray, count: int) -> np.ndarray:
    index = np.flatnonzero(mask)
    return index[:: max(1, len(index) // count)]


def propose(rec, kin, residual: np.ndarray, torque: np.ndarray, fold: np.ndarray, train: np.ndarray,
            test: np.ndarray, smoothed: bool) -> dict | None:
    """The sparse term that best predicts `residual` on the held-out folds, or None."""
    ok = np.isfinite(residual)
    tr, te = _sampled(train & ok, SAMPLES), _sampled(test & ok, SAMPLES)
    if len(tr) < 100 or len(te) < 100:
        return None
    names, columns = [], []
    for name, column in features(rec, kin, np.nan_to_num(torque)).items():
        column = kin.smooth(column) if smoothed else column
        names.append(name)
        columns.append(column[np.concatenate([tr, te])])
    X = np.column_stack(columns)
    mean, std = X[: len(tr)].mean(axis=0), X[: len(tr)].std(axis=0)
    usable = std > 1e-12
    X = (X[:, usable] - mean[usable]) / std[usable]
    names = [n for n, u in zip(names, usable) if u]
    y = residual[np.concatenate([tr, te])]
    y_train, y_test = y[: len(tr)], y[len(tr):]
    offset = y_train.mean()
    before = (y_test - offset) ** 2
    # The whole pursuit path at once (1..MAX_TERMS terms) from the training Gram matrix.
    # scikit-learn is imported here: it costs 0.4 s, and most diagnoses never propose a term.
    from sklearn.linear_model import orthogonal_mp_gram
    X_train, X_test = X[: len(tr)], X[len(tr):]
    path = orthogonal_mp_gram(X_train.T @ X_train, X_train.T @ (y_train - offset), n_nonzero_coefs=MAX_TERMS,
                              return_path=True)
    path = path.reshape(len(names), -1)
    best = None
    for coef in path.T:
        after = (y_test - offset - X_test @ coef) ** 2
        if best is None or after.mean() < best[1].mean() * 0.99:  # one more term must earn its place
            best = (coef, after)
    coef, after = best
    gain = held_out_gain_sq(before, after, fold[te], np.ones(len(te), bool))
    if gain.gain < PROPOSAL_MIN_GAIN or gain.z < EVIDENCE_Z:
        return None
    chosen = np.flatnonzero(coef)
    coefficients = {names[j]: float(coef[j] / std[usable][j]) for j in chosen}
    order = sorted(coefficients, key=lambda n: -abs(coef[names.index(n)]))
    return {"terms": " + ".join(f"{coefficients[n]:.4g}*{n}" for n in order),
            "coefficients": {n: coefficients[n] for n in order},
            "holdout_gain": round(gain.gain, 4), "z": round(gain.z, 1)}


def propose_terms(diag, p: dict, unexplained: list[dict]) -> list[dict]:
    """The fallback for a diagnosis: one proposal per channel with unexplained structure."""
    out = []
    for channel in diag.channels:
        if not any(u.get("channel") == channel.name for u in unexplained):
            continue
        proposal = propose(diag.rec, diag.prep.kin, diag.shown_residual(channel, p), diag.reference_torque(p),
                           diag.fold, diag.train, diag.test, channel.smoothed())
        if proposal:
            out.append(dict(proposal, channel=channel.name))
    return out
