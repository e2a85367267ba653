"""The diagnosis from recordings to its findings document, stage by stage,
each taking the results of those before it:

  prepare    the recordings checked and joined, folds, fit sample, channels (model/prepare.py)
  calibrate  the nominal model's parameters, MAP with tolerance priors, and the noise (fit/nominal_calibration.py, fit/objective.py)
  locate     structure in the calibrated residuals (findings.remaining_structure; beside select's first round)
  select     forward selection over the effects the recording can test (search/selection.py, search/hypothesis_search.py)
  resize     parameters the nominal model has, needed beyond their tolerance (verdict/resize.py)
  limits     the smallest size of each untold effect the recording would show (verdict/detection_limit.py)
  accuracy   each channel's residual against its sensors' floor and the accuracy asked for (verdict/floors.py; beside limits)
  document   findings.json (verdict/findings.py), with terms proposed for what no effect explains (verdict/open_library.py)
"""
from __future__ import annotations

import time
from typing import Callable

from threadpoolctl import threadpool_limits

from hdjoint.diagnosis.fit.nominal_calibration import calibrate, calibration_table
from hdjoint.diagnosis.verdict.detection_limit import detection_limits
from hdjoint.diagnosis.verdict.findings import document, remaining_structure
from hdjoint.diagnosis.verdict.floors import accuracy
from hdjoint.diagnosis.forked import Deferred
from hdjoint.diagnosis.verdict.open_library import propose_terms
from hdjoint.diagnosis.model.prepare import prepare
from hdjoint.diagnosis.verdict.resize import released, resized
from hdjoint.diagnosis.results import DiagnosisResult
from hdjoint.diagnosis.search.hypothesis_search import HypothesisSearch
from hdjoint.diagnosis.search.selection import select, unconfirmed_structure
from hdjoint.io.recording import Recording


def diagnose(rec: Recording | list[Recording], nominal: dict[str, float],
             progress: Callable[[str], None] | None = None, tolerance: dict[str, float] | None = None,
             workers: int | None = None, accuracy: float | None = None, noise: dict[str, float] | None = None,
             when_settled: Callable | None = None):
    """Run every stage on one recording or several of the same joint (fitted
    jointly); returns (the DiagnosisResult, the findings document). The
    hypotheses of each round are fitted by `workers` processes (None: one
    per core; 1: in this process), with the same results. `accuracy`: the
    torque accuracy asked of the model, N.m (None: rules.ACCURACY_SHARE of
    the torque span); `noise`: sensors' stated noise ({"i_m": A RMS,
    "tau_sensor": N.m RMS}; the others are measured on the recording).
    `when_settled(objective, calibrated set, corrected set, findings)` is called
    as soon as the corrected set is final, before the detection limits: a
    caller may start on it meanwhile (the report's figures)."""
    # The linear algebra here is tall and thin (thousands of samples by a
    # dozen parameters): one BLAS thread is faster than several fighting over two cores.
    with threadpool_limits(limits=1, user_api="blas"):
        return _diagnose(rec, nominal, progress, tolerance, workers, accuracy, noise, when_settled)


def _diagnose(rec, nominal, progress, tolerance, workers, stated_accuracy=None, stated_noise=None,
              when_settled=None):
    setup = prepare(rec, nominal, tolerance, progress, workers)
    calibrated = calibrate(setup)
    objective = calibrated.objective
    # Structure in the calibrated residuals is located beside the first round of hypotheses, which would
    # leave a core idle at its end.
    located = Deferred(lambda: remaining_structure(objective, calibrated.params))
    search = HypothesisSearch(objective, calibrated.current_alignment)
    selection = select(search, calibrated, beside=located)
    p = selection.params
    calibration = calibration_table(objective, selection.last_fit, p)
    setup.say("checking what remains")
    gross = released(objective, selection, calibration)  # a link model far off, before the priors hold it short
    if gross.selection is not selection:  # the corrected set carries a released estimate
        selection = gross.selection
        p = selection.params
        calibration = calibration_table(objective, selection.last_fit, p)
    settled = {c.name for f in gross.findings for c in f.resized} | {u["parameter"] for u in gross.unexplained}
    resized_findings, unattributed = resized(objective, selection, calibration, settled)
    resized_findings = sorted(gross.findings + resized_findings, key=lambda f: f.p_value)
    unattributed += gross.unexplained
    if when_settled is not None:
        when_settled(objective, calibrated.params, p, selection.findings + resized_findings)
    setup.say("measuring the smallest size of each untold effect this recording would show, and each "
              "channel's residual against its sensors' floor")
    size = Deferred(lambda: accuracy(objective, p, selection.not_testable, stated_accuracy, stated_noise))
    limits = detection_limits(search, selection, {e for f in selection.findings + resized_findings
                                                  for e in f.named()}, beside=size)
    size = size.result()
    result = DiagnosisResult(objective, calibrated, selection, search, selection.findings + resized_findings, calibration,
                             located.result(), remaining_structure(objective, p) + unconfirmed_structure(selection, objective)
                             + unattributed + size.beyond, limits, size)
    doc = document(result)
    if doc["unexplained"]:  # open-library fallback: propose terms for what no named effect explains
        doc["proposed_terms"] = propose_terms(objective, p, doc["unexplained"])
    doc["seconds"] = round(time.perf_counter() - setup.started, 2)
    return result, doc
