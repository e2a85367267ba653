"""An independent truth for the diagnosis benchmark: a harmonic-drive joint
written in Python from the paper's equations and the contract's sign
conventions, never through hdjoint._core or the FMUs, whose model FORM is
drawn per seed (friction law and smoothing, hysteresis law, integrator and
step, sensor chain), so that a benchmark on it shows what the diagnosis'
model form gets wrong and not only what its parameters do.

  physics.py      the joint's laws (one function each) and the drawn form
  sensors.py      encoders (floor/round quantiser, interpolation error),
                  the current sensor chain, sampling jitter
  excitations.py  link position references (paper, multisine, sweep, constant speeds, chirp)
  simulate.py     the digital controller and the fixed-step integrators
  cases.py        benchmark cases: an effect concealed, the nominal set, seeds
  outside.py      physics outside the diagnosis's effect library, and a LuGre control
"""
