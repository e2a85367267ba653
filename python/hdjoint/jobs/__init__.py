"""Whole jobs from files to files, shared by the command line, the demo and
the fleet: the user's inputs and outputs checked before any work (inputs),
estimation (estimate) and diagnosis (diagnose)."""
