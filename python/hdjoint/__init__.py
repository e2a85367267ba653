"""hdjoint: torque estimation for harmonic-drive robot joints."""
