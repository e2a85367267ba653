"""Torque estimation over whole recordings: the FMU and batch engines
(engines), the offline smoother (smoother), error figures (metrics) and the
paper's table (paper_table)."""
