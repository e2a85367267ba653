"""The second truth: a harmonic-drive joint simulator written apart from the
diagnosis (issue 53, goal 1), to examine it from outside.

joint.py (the ODE), controller.py (the drive), excitations.py, simulate.py
(solve_ivp per sample), recording.py (sensors -> contract CSV), nominal.py
(what the user types vs the truth), forms/ (model forms and nuisances, one
per file), effects/ (planted missing physics, one per file), cases.py (seeds,
cases, CLI). Imports nothing of hdjoint (tests/second_truth/test_independence.py).
"""
