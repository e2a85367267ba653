"""The calibration's priors and posteriors.

Every calibrated parameter has a prior: a normal around its nominal value
whose standard deviation is its tolerance (src/hdjoint/parameter_tolerance.def,
overridable per parameter in the parameter file). The fit is the maximum a
posteriori; its posterior is the Laplace (Gauss-Newton) approximation at the
optimum, widened where the data say it is too narrow: a cluster-robust
("sandwich") covariance over contiguous blocks of the recording, which
sees residuals that are correlated or carry model-form error (a friction
law of another shape, unmodelled damping) as the scatter of the blocks'
scores, where the Laplace approximation assumes white residuals. Each
parameter's interval is the wider of the two, times its model-form factor:
how much wider the interval must be to contain the truth at the INTERVAL
rate on joints simulated by independently written code (another friction
law, integrator, sensor chain), fitted and checked on separate draws by
benchmarks/interval_coverage.py (1 for a parameter it has no factor for). A parameter is identified by the recording when its posterior is
less than half as wide as its prior, and moved beyond its tolerance when
its estimate lies more than RESIZE_Z tolerances from the nominal value.
"""
from __future__ import annotations

import json
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

from hdjoint.diagnosis import normal as norm
from hdjoint.io import parameters
from hdjoint.diagnosis.rules import IDENTIFIED_RATIO, INTERVAL_Z, RESIZE_Z

# Written by benchmarks/interval_coverage.py --fit-factors, with where it was measured.
MODEL_FORM_FACTORS = Path(__file__).with_name("model_form_factors.json")


@lru_cache(maxsize=1)
def model_form_factors() -> dict[str, float]:
    """Each parameter's model-form factor (>= 1); parameters never measured are left out (factor 1)."""
    if not MODEL_FORM_FACTORS.exists():
        return {}
    return {n: max(1.0, float(f)) for n, f in json.loads(MODEL_FORM_FACTORS.read_text())["factors"].items()}


def widened(name: str, std: float) -> float:
    """A posterior standard deviation widened by the parameter's model-form factor."""
    return std * model_form_factors().get(name, 1.0)


@dataclass(frozen=True)
class Prior:
    centre: float
    std: float


def priors(names, nominal: dict, tolerance: dict[str, float], centres: dict | None = None) -> dict[str, Prior]:
    """A prior for each name: around its nominal value (or `centres[name]`),
    one tolerance wide (the user's relative `tolerance` overrides the table's)."""
    table = parameters.table()
    out = {}
    for n in names:
        info = table[n]
        if not info.calibrated():
            raise ValueError(f"parameter '{n}' has no tolerance in parameter_tolerance.def: it cannot be calibrated")
        value = nominal.get(n, info.default)
        out[n] = Prior((centres or {}).get(n, value), info.tolerance(value, tolerance.get(n)))
    return out


def posterior_std(jacobian: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Laplace standard deviations from the Jacobian of the whitened residuals
    (data and priors) in the fit's scaled coordinates."""
    return deviations(np.linalg.pinv(jacobian.T @ jacobian), scale)


def robust_std(jacobian: np.ndarray, residuals: np.ndarray, blocks: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """Cluster-robust standard deviations, H^-1 (S + P) H^-1: H the Gauss-Newton
    information (data and priors), S the spread of the data's score over the
    blocks (`blocks`: a label per data row, rows past them are the priors'),
    P the priors' information. Equal to posterior_std when the residuals are
    white and the model's form is right."""
    return deviations(robust_covariance(jacobian, residuals, blocks), scale)


def robust_covariance(jacobian: np.ndarray, residuals: np.ndarray, blocks: np.ndarray) -> np.ndarray:
    """robust_std's covariance in the fit's scaled coordinates (Laplace's with fewer than 3 blocks)."""
    info = jacobian.T @ jacobian
    n = len(blocks)
    scores = jacobian[:n] * residuals[:n, None]
    labels, which = np.unique(blocks, return_inverse=True)
    inverse = np.linalg.pinv(info)
    if len(labels) < 3:
        return inverse
    per_block = np.zeros((len(labels), jacobian.shape[1]))
    np.add.at(per_block, which, scores)
    per_block -= per_block.mean(axis=0)  # with priors the data's score sums to the priors', not to 0
    meat = per_block.T @ per_block * len(labels) / (len(labels) - 1) + jacobian[n:].T @ jacobian[n:]
    return inverse @ meat @ inverse


def correlation(cov: np.ndarray) -> np.ndarray:
    """The correlation matrix of a covariance (0 off the diagonal of a parameter with no spread)."""
    sd = np.sqrt(np.clip(np.diag(cov), 0.0, None))
    with np.errstate(divide="ignore", invalid="ignore"):
        r = np.where(np.outer(sd, sd) > 0.0, cov / np.outer(sd, sd), 0.0)
    np.fill_diagonal(r, 1.0)
    return np.clip(r, -1.0, 1.0)


def deviations(cov: np.ndarray, scale: np.ndarray) -> np.ndarray:
    """The standard deviations of a covariance in the fit's scaled coordinates, in the parameters' units."""
    return np.sqrt(np.clip(np.diag(cov), 0.0, None)) * scale


@dataclass
class Calibrated:
    name: str
    nominal: float
    estimate: float
    std: float          # posterior: the wider of Laplace and sandwich
    prior: Prior

    @property
    def interval(self) -> tuple[float, float]:
        info = parameters.table()[self.name]
        half = INTERVAL_Z * self.std
        return max(self.estimate - half, info.min), min(self.estimate + half, info.max)

    @property
    def z(self) -> float:
        return (self.estimate - self.prior.centre) / self.prior.std

    @property
    def identified(self) -> bool:
        return self.std < IDENTIFIED_RATIO * self.prior.std

    @property
    def beyond_tolerance(self) -> bool:
        return abs(self.z) > RESIZE_Z

    @property
    def p_value(self) -> float:
        """Two-sided probability of |z| this large were the parameter within its prior."""
        return float(2.0 * norm.sf(abs(self.z)))

    def as_dict(self) -> dict:
        lo, hi = self.interval
        return {"nominal": self.nominal, "estimate": self.estimate, "lo": lo, "hi": hi,
                "tolerance": self.prior.std, "z": round(self.z, 3), "identified": bool(self.identified),
                "interval": "laplace or sandwich, the wider, times the model-form factor "
                            f"{model_form_factors().get(self.name, 1.0):.2f}"}
