"""The mismatch diagnosis: where a model and a recording differ, which
physics is left out, the corrected parameter set, and the report.
docs/diagnosis.md says how it works; docs/architecture.md lists the modules."""
