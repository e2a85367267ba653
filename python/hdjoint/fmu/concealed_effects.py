"""Benchmark cases for the diagnosis: recordings of simulated joints where
one effect (or several, or none) is missing from the nominal model, and
concealed: about the size of the noise and quantisation in the time
domain, present only in some regime, and mixed with a few percent of error
in the nominal parameters.

The truth uses other parametrisations than the hypotheses the diagnosis
fits, so a hit is not the model recognising itself: LuGre friction is to be
found as Stribeck/Coulomb, Bouc-Wen hysteresis as Dahl, an exponential
warm-up as a linear drift, a smooth current lag as a pure delay.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from hdjoint.fmu import experiments
from hdjoint.io import parameters
from hdjoint.io.recording import Recording

# A few percent of error in what the user believes (the nominal set) against the truth.
PARAMETER_ERRORS = {"Kt": 1.03, "Kf": 0.96, "Jm": 1.04, "Fc": 1.05, "Bm": 0.95, "al1": 1.1, "aw1": 0.92,
                    "bw1": 1.08, "Cf": 1.05}


@dataclass
class Case:
    name: str
    present: tuple[str, ...]            # effect IDs the truth has and the nominal lacks
    truth: dict = field(default_factory=dict)    # truth parameters beyond the nominal ones
    nominal_off: dict = field(default_factory=dict)  # how the nominal set switches an effect off
    current_lag: float = 0.0            # s, a first-order lag of the current sensor (time_delay truth)
    seed: int = 1


CASES = [
    Case("control A (nothing missing)", ()),
    Case("control B (nothing missing, other noise)", (), seed=7),
    Case("kinematic error, 3rd and 5th motor order", ("kinematic_error",),
         truth={"ke_m1_order": 3.0, "ke_m1_a": 6e-6, "ke_m1_b": -4e-6, "ke_m2_order": 5.0, "ke_m2_a": 4e-6}),
    Case("wave generator compliance", ("wave_generator_compliance",),
         truth={"Kw": 40.0, "Cw": 10.0}, nominal_off={"Kw": 1e9, "Cw": 0.0}),
    Case("wave generator load (the paper's approximation)", ("wave_generator_load",),
         nominal_off={"wg_load": 0.0}),
    Case("stiffness nonlinearity", ("stiffness_nonlinearity",), truth={"Cf": 0.0645}, nominal_off={"Cf": 0.0}),
    # Bouc-Wen with gamma != 0 (with gamma = 0 and n = 1 it would be Dahl
    # itself): saturation A/(beta+gamma) = 0.1 N.m, unequal branch slopes.
    Case("hysteresis (Bouc-Wen truth)", ("hysteresis",), truth={"bw_A": 3e4, "bw_beta": 2e5, "bw_gamma": 1e5}),
    Case("backlash", ("backlash",), truth={"backlash": 2.0e-5}),
    Case("Coulomb friction (LuGre truth)", ("coulomb_friction",),
         truth={"lugre_sigma0": 2e3, "lugre_sigma1": 0.5}, nominal_off={"Fc": 0.0}),
    Case("Stribeck friction (LuGre truth)", ("stribeck_friction",),
         truth={"lugre_sigma0": 2e3, "lugre_sigma1": 0.5, "Fs": 0.01, "omega_s": 8.0}),
    Case("viscous friction", ("viscous_friction",), truth={"Bm": 1.5e-4}, nominal_off={"Bm": 0.0}),
    Case("cogging, 6th motor order", ("cogging",), truth={"cog_order": 6.0, "cog_a": 1.2e-3, "cog_b": 0.8e-3}),
    Case("time delay (lagging current sensor)", ("time_delay",), current_lag=2.5e-3),
    Case("thermal drift (exponential warm-up)", ("thermal_drift",),
         truth={"thermal_gain": -0.35, "thermal_tc": 15.0}),
    Case("gravity load", ("gravity_load",), truth={}, nominal_off={"mgl": 0.0}),
    Case("link friction", ("link_friction",), truth={"Fl": 0.25}),
    Case("several: kinematic error + hysteresis + Stribeck", ("kinematic_error", "hysteresis", "stribeck_friction"),
         truth={"ke_m1_order": 3.0, "ke_m1_a": 6e-6, "ke_m1_b": -4e-6, "bw_A": 3e4, "bw_beta": 2e5,
                "bw_gamma": 1e5, "lugre_sigma0": 2e3, "lugre_sigma1": 0.5, "Fs": 0.01, "omega_s": 8.0}),
]


def nominal_for(case: Case) -> dict[str, float]:
    """What the user believes: defaults with the wave generator loaded as in
    the joint FMU (wg_load = 1), and the case's effect switched off."""
    nominal = dict(parameters.defaults(), wg_load=1.0)
    nominal.update(case.nominal_off)
    return nominal


def truth_for(case: Case) -> dict[str, float]:
    """The simulated joint: the nominal set off by a few percent, plus the effect."""
    nominal = parameters.defaults()
    truth = dict(nominal)
    for name, factor in PARAMETER_ERRORS.items():
        truth[name] *= factor
    truth.update(case.truth)
    return truth


def record(case: Case, duration: float = 30.0, experiment: str = "paper") -> Recording:
    """Simulate the case's joint on an experiment (the paper's by default) and record it."""
    rec = experiments.run(experiment, joint=truth_for(case), nominal=nominal_for(case), duration=duration,
                          sensors=experiments.Sensors(seed=case.seed))
    if case.current_lag > 0.0:
        rec.i_m = _lagged(rec.time, rec.i_m, case.current_lag)
    return rec


def _lagged(t, x, tau):
    """A first-order sensor lag with time constant tau (not a pure delay)."""
    a = 1.0 - np.exp(-np.median(np.diff(t)) / tau)
    y = np.empty_like(x)
    y[0] = x[0]
    for k in range(1, len(x)):
        y[k] = y[k - 1] + a * (x[k] - y[k - 1])
    return y
