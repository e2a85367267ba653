"""The calibration stage: the nominal model's own parameters (those it
switches on, plus offsets, gains and shape parameters) fitted on the
training folds, maximum a posteriori with each parameter's tolerance as its
prior (calibration.py), with an interval for each. Its noise scales come
from a first pass's residuals, and the current's alignment against the
encoders (a property of the recording, current_alignment.py) from its
parameters."""
from __future__ import annotations

from dataclasses import dataclass

from hdjoint.diagnosis.fit.priors import Calibrated, priors
from hdjoint.diagnosis.model.current_alignment import align_current
from hdjoint.diagnosis.effects import calibrated_parameters
from hdjoint.diagnosis.fit.objective import Fit
from hdjoint.diagnosis.fit.objective import Objective
from hdjoint.diagnosis.model.prepare import Setup
from hdjoint.io import parameters


@dataclass(frozen=True)
class Calibration:
    params: dict                    # the calibrated set
    fit: Fit
    objective: Objective            # with the noise measured at the calibrated set, for every later stage
    current_alignment: dict | None  # None: no motor channel


def calibrate(setup: Setup) -> Calibration:
    setup.say("calibrating the nominal model's parameters (maximum a posteriori)")
    start = Objective(setup)
    p = start.initial_offset(setup.nominal)
    names = []
    for part in ("transmission", "motor", "link"):
        if setup.channels_of(part):
            names += [n for n in calibrated_parameters(part, setup.nominal, setup.has_sensor) if n not in names]
    objective = Objective(setup, priors(names, setup.nominal, setup.tolerance, centres={"a0": p["a0"]}),
                          names).with_noise(p)
    alignment = None
    for first in (True, False):
        fit = objective.fit(p, names, setup.channels)
        p = fit.params
        if first:
            alignment = align_current(objective, p)
        objective = objective.with_noise(p)
    return Calibration(p, fit, objective, alignment)


def calibration_table(objective: Objective, fit: Fit, p: dict) -> dict[str, Calibrated]:
    """Each calibrated parameter: nominal, estimate at `p`, its posterior std from `fit`, and its prior."""
    return {n: Calibrated(n, objective.nominal.get(n, parameters.table()[n].default), p[n],
                          fit.std.get(n, objective.priors[n].std), objective.priors[n])
            for n in objective.calibrated_names}
