"""The joint's model of a recording: kinematics, torque estimates per part, residual channels, the prepared Setup."""
