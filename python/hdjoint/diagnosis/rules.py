"""Every threshold the diagnosis decides by, once, with its meaning and where
its value comes from. Stages and effects import these names; no other module
writes a decision threshold as a bare number.

Where a value was set by measurement, the benchmark that measures it is
named; its figures are in docs/results/, not here.
"""
from __future__ import annotations

from hdjoint.diagnosis import normal

# --- What a recording must have -------------------------------------------
MIN_SAMPLES = 500      # fewer samples than this cannot fill the held-out folds
MIN_DURATION = 2.0     # s: shorter recordings hold no repeated motion to compare folds over

# --- How the data is split ------------------------------------------------
FIT_SAMPLES = 5000     # training samples a fit looks at (spread over all training blocks)
FOLDS = 40             # contiguous blocks; even ones fit, odd ones are held out
# Contiguous blocks over which the robust (sandwich) posterior compares the
# data's scores: each far longer than the residual's correlation.
SCORE_BLOCKS = 100
# A longer recording is analysed in FOLDS windows spread over it, this long
# in all: the diagnosis time then stops growing with the recording's length.
ANALYSED_SECONDS = 120.0
# A hypothesis's fit stops when its cost changes by less than this (relative):
# its held-out gain is judged to 0.1 %, not to the default 1e-8.
HYPOTHESIS_FTOL = 1e-6

# --- Evidence for a hypothesis (Hypothesis.accepted) ----------------------
# Benjamini-Hochberg false-discovery rate over a round's hypotheses; the
# false-alarm rate it gives on controls: docs/results/false_alarms_*.md and
# diagnosis_independent.md.
FALSE_DISCOVERY_RATE = 0.05
# The held-out gain (share of the held-out residual explained) a hypothesis must exceed.
MIN_GAIN = 0.003
# z of the mean fold improvement over its standard error: the conventional
# three standard errors, used for every "stands out of the folds' scatter".
EVIDENCE_Z = 3.0
# A stationary effect improves at least this share of the held-out folds.
STEADY_FOLD_SHARE = 0.7
# Bayesian information criterion: delta BIC below -10 is "very strong"
# support (Kass & Raftery 1995, J. Am. Stat. Assoc. 90, table p. 777).
SEEN_BIC = -10.0

# --- Telling look-alikes apart --------------------------------------------
# The better look-alike's held-out gain beats the other's by this many
# standard errors over the folds, and the other explains at most this share
# of what the better one does; otherwise both are reported together.
SEPARATED_Z = 2.0
SEPARATED_RATIO = 0.8

# --- What is left after the search ----------------------------------------
# A hypothesis explaining at least this share of the held-out residual that the
# simulated null does not confirm leaves the verdict `unexplained`, not `consistent`.
UNCONFIRMED_GAIN = 0.5
# Residual structure (a feature or an order) counts when it explains this
# share of the held-out residual with EVIDENCE_Z.
STRUCTURE_GAIN = 0.005
# Where the residual is located (findings.remaining_structure): a feature
# explaining this share held out, with this z, before the p-value is read.
LOCATED_GAIN = 0.02
LOCATED_Z = 4.0
# A link order the travel does not resolve is tried when it explains this share
# of a channel's held-out residual.
UNRESOLVED_GAIN = 0.005
# An order that alone explains this share of the held-out residual is a ripple
# whatever its off-orders carry (benchmarks/order_gate_scan.py measures the gate).
DOMINANT_GAIN = 0.30
# An order stands out of its off-orders' floor by this factor.
ORDER_PROMINENCE = 3.0

# --- The verdict's absolute yardstick (verdict/floors.py) -------------------------
# The accuracy a model must reach, by default, as a share of the torque span:
# torque estimators and sensors of this class state a few % of their range.
ACCURACY_SHARE = 0.05
# A model missing more than this share of the torque span is never
# `consistent`, whatever accuracy is stated (issue 38).
MAX_MISS_SHARE = 0.10
# The torque span: between these percentiles of the torque the joint carries
# (the extremes of a real log hold spikes).
TORQUE_SPAN_PERCENTILES = (2.0, 98.0)
# A standstill long enough to measure a sensor's scatter at (samples).
STANDSTILL_SAMPLES = 50

# --- Calibration ----------------------------------------------------------
# Parameters a user often takes from another joint (a catalogue's stiffness, a
# CAD link model) and may have off by a factor, not by a tolerance: with their
# tolerance as prior, the calibration holds them near a grossly wrong nominal
# value (issue 38: mgl 4 N.m on an arm whose torque swings over 190 N.m). The
# resize stage refits them with the prior GROSS_FACTOR times the nominal value
# wide (resize.released); an estimate beyond GROSS_FACTOR times the nominal
# value either way is another part, not a mis-sized one.
GROSS_CHECKED = ("mgl", "Jl", "Kf")
GROSS_FACTOR = 25.0
# One of them whose released INTERVAL lies wholly beyond this factor of its
# nominal value either way is resized even within RESIZE_Z tolerances: a
# flexspline 2.5 times softer sits 3 tolerances of 20 % off, not beyond, and
# the rest of the calibration takes up much of it when it is held there.
GROSS_RATIO = 2.0
RESIZE_Z = 3.0          # |estimate - nominal| / tolerance beyond which a parameter counts as resized
IDENTIFIED_RATIO = 0.5  # posterior std / prior std below which the recording identifies a parameter
INTERVAL = 0.95         # every fitted parameter's interval
INTERVAL_Z = float(normal.ppf(0.5 + INTERVAL / 2))  # its half-width in standard deviations (1.96)

# --- What the recording cannot tell (cannot_tell) -------------------------
SEEN_GAIN = 0.02        # a hypothesis explaining this much, with SEEN_BIC, was seen though not accepted
ABSORBED_Z = 5.0        # a calibrated parameter this many posterior stds off took an effect's place

# --- Proposing terms outside the library (open_library) -------------------
PROPOSAL_MIN_GAIN = 0.01  # a proposed regression must explain this share held out (with EVIDENCE_Z)


def steady_over_folds(gain) -> bool:
    """A stationary effect helps most held-out folds: EVIDENCE_Z over them,
    and at least STEADY_FOLD_SHARE of them improved."""
    return gain.z > EVIDENCE_Z and gain.folds_improved >= STEADY_FOLD_SHARE * gain.folds_compared


def passes(gain, p_value: float, uneven_over_folds: bool) -> bool:
    """The held-out part of a hypothesis's acceptance: above MIN_GAIN,
    significant, and steady over the folds unless the effect is uneven over
    them by nature (then its p-value against the simulated null decides)."""
    if gain.gain <= MIN_GAIN or p_value > FALSE_DISCOVERY_RATE:
        return False
    return uneven_over_folds or steady_over_folds(gain)
