"""The shipped FMUs and what runs them: their paths and export (shipped),
stepping them through fmpy (runner), built-in experiments (experiments),
joints with a concealed effect for benchmarks and fleets (concealed_effects),
and the SSP systems in co-simulation masters (cosim)."""
