"""What a diagnosis returns besides its findings document: every stage's
result, read by findings, report, validation and the benchmarks."""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from hdjoint.diagnosis.calibration import Calibrated
from hdjoint.diagnosis.hypotheses import Finding


@dataclass
class DiagnosisResult:
    """What a diagnosis found, for findings.py and report.py to read."""
    engine: Any                       # the Diagnosis: residuals and signals, for figures and figures of merit
    nominal: dict
    calibrated_params: dict           # after calibration, before any finding
    params: dict                      # the corrected set
    findings: list[Finding]
    calibration: dict[str, Calibrated]
    tested: list[list[dict]]
    not_testable: list[dict]
    sigma: dict[str, float]
    located: list[dict] = field(default_factory=list)
    unexplained: list[dict] = field(default_factory=list)
    orders_not_found: list[dict] = field(default_factory=list)
    limits: list = field(default_factory=list)  # detection_limit.Limit per effect tested and not accepted

    @property
    def beyond_tolerance(self) -> list[Calibrated]:
        return [c for c in self.calibration.values() if c.beyond_tolerance]
