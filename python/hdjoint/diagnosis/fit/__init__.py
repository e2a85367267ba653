"""Fitting the model: the MAP objective, priors and posteriors, the nominal calibration."""
