"""What a diagnosis returns besides its findings document: each stage's
result, read by findings, report, validation and the benchmarks."""
from __future__ import annotations

from dataclasses import dataclass, field

from hdjoint.diagnosis.fit.nominal_calibration import Calibration
from hdjoint.diagnosis.fit.priors import Calibrated
from hdjoint.diagnosis.verdict.floors import Accuracy
from hdjoint.diagnosis.fit.objective import Fit
from hdjoint.diagnosis.search.hypotheses import Finding
from hdjoint.diagnosis.fit.objective import Objective
from hdjoint.diagnosis.search.hypothesis_search import HypothesisSearch
from hdjoint.diagnosis.search.selection import Selection


@dataclass(frozen=True)
class DiagnosisResult:
    objective: Objective              # residuals and signals at the calibrated noise, for figures and figures of merit
    calibrated: Calibration           # the calibration stage
    selection: Selection              # the selection stage
    search: HypothesisSearch          # the search as the selection left it (its last round's null), for the limits
    findings: list[Finding]           # added and resized
    calibration: dict[str, Calibrated]  # each calibrated parameter at the corrected set
    located: list[dict] = field(default_factory=list)      # structure in the calibrated model's residuals
    unexplained: list[dict] = field(default_factory=list)  # structure no finding explains
    limits: list = field(default_factory=list)  # detection_limit.Limit per effect tested and not accepted
    accuracy: Accuracy | None = None  # each channel's residual against its floor and the accuracy asked for

    @property
    def nominal(self) -> dict:
        return self.objective.nominal

    @property
    def calibrated_params(self) -> dict:
        """After calibration, before any finding."""
        return self.calibrated.params

    @property
    def params(self) -> dict:
        """The corrected set."""
        return self.selection.params

    @property
    def last_fit(self) -> Fit:
        return self.selection.last_fit

    @property
    def current_alignment(self) -> dict | None:
        return self.calibrated.current_alignment

    @property
    def tested(self) -> list[list[dict]]:
        return self.selection.tested

    @property
    def not_testable(self) -> list[dict]:
        return self.selection.not_testable

    @property
    def orders_not_found(self) -> list[dict]:
        return self.selection.orders_not_found

    @property
    def sigma(self) -> dict[str, float]:
        return dict(self.objective.sigma)

    @property
    def beyond_tolerance(self) -> list[Calibrated]:
        return [c for c in self.calibration.values() if c.beyond_tolerance]
