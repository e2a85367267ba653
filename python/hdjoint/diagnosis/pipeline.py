"""The diagnosis from a recording to its findings document, stage by stage:
calibrate, locate, select effects, resize, measure detection limits,
document, and propose terms for what no effect explains."""
from __future__ import annotations

import time as _time
from typing import Callable

from threadpoolctl import threadpool_limits

from hdjoint.diagnosis.detection_limit import detection_limits
from hdjoint.diagnosis.engine import Diagnosis, DiagnosisResult
from hdjoint.diagnosis.findings import document, remaining_structure
from hdjoint.diagnosis.open_library import propose_terms
from hdjoint.io.recording import Recording


def diagnose(rec: Recording | list[Recording], nominal: dict[str, float],
             progress: Callable[[str], None] | None = None, tolerance: dict[str, float] | None = None,
             workers: int | None = None):
    """Run every step on one recording or several of the same joint (fitted
    jointly); returns (the DiagnosisResult, the findings document). The
    hypotheses of each round are fitted by `workers` processes (None: one
    per core; 1: in this process), with the same results."""
    # The linear algebra here is tall and thin (thousands of samples by a
    # dozen parameters): one BLAS thread is faster than several fighting
    # over two cores, by up to 7x measured on this machine under load.
    with threadpool_limits(limits=1, user_api="blas"):
        return _diagnose(rec, nominal, progress, tolerance, workers)


def _diagnose(rec, nominal, progress, tolerance, workers):
    diag = Diagnosis(rec, nominal, progress, tolerance, workers)
    calibrated, diag.last_fit = diag.calibrate()
    diag.say("locating structure in the calibrated model's residuals")
    located = remaining_structure(diag, calibrated)
    p, added = diag.select(calibrated)
    calibration = diag.calibration_of(diag.last_fit, p)
    diag.say("checking what remains")
    resized, unattributed = diag.resized(calibration, p)
    diag.say("measuring the smallest size of each untold effect this recording would show")
    limits = detection_limits(diag, p, {e for f in added + resized for e in f.named()})
    result = DiagnosisResult(diag, dict(diag.nominal), dict(calibrated), p, added + resized,
                             calibration, diag.tested, diag.not_testable, dict(diag.sigma), located,
                             remaining_structure(diag, p) + diag.unconfirmed_structure() + unattributed,
                             diag.orders_not_found, limits)
    doc = document(result)
    if doc["unexplained"]:  # open-library fallback: propose terms for what no named effect explains
        doc["proposed_terms"] = propose_terms(diag, p, doc["unexplained"])
    doc["seconds"] = round(_time.perf_counter() - diag.started, 2)
    return result, doc
