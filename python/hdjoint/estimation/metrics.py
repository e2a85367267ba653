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


class RunningErrorFigures:
    """error_figures over a signal that arrives block by block (a streamed recording)."""

    def __init__(self):
        self._sum_squares, self._count, self._max = 0.0, 0, 0.0

    def add(self, estimate, reference) -> None:
        e = np.asarray(estimate, float) - np.asarray(reference, float)
        e = e[np.isfinite(e)]
        if e.size:
            self._sum_squares += float(np.dot(e, e))
            self._count += e.size
            self._max = max(self._max, float(np.max(np.abs(e))))

    def result(self) -> ErrorFigures:
        rms = float(np.sqrt(self._sum_squares / self._count)) if self._count else float("nan")
        return ErrorFigures(rms, self._max if self._count else float("nan"))
