"""Error figures of a torque estimate against a reference torque."""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class ErrorFigures:
    rms: float
    max: float

    def reduction_against(self, baseline: "ErrorFigures") -> float:
        """Relative RMS reduction, in percent (positive: better than baseline)."""
        return 100.0 * (1.0 - self.rms / baseline.rms)


def error_figures(estimate, reference) -> ErrorFigures:
    e = np.asarray(estimate, float) - np.asarray(reference, float)
    e = e[np.isfinite(e)]
    return ErrorFigures(float(np.sqrt(np.mean(e * e))), float(np.max(np.abs(e))))
