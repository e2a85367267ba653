"""Fleet scale: diagnose or estimate a whole folder of recordings on Dask
(`hdjoint fleet ...`), resumably, and report which joints drift.

  inputs.py   which recordings, which parameter file and joint id each one has
  store.py    results keyed by content hash, written atomically
  tasks.py    the work one worker does for one recording (returns a small row)
  rows.py     a findings document flattened into a row
  run.py      the cluster, submission, retries, progress, fleet.parquet
  trend.py    the trend test and the drift ranking
  report.py   fleet.html
  generate.py a simulated fleet with known drifts (the proof)
  cli.py      the `hdjoint fleet` subcommands
"""
