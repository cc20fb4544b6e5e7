"""Arm + fingers inverse kinematics among obstacles (seed 001)."""
