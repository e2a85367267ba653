"""The second truth: an independent harmonic-drive joint simulator (issue 53, goal 1)."""
