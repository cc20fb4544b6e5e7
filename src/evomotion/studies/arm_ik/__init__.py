"""Arm + fingers inverse kinematics among obstacles (paper 001)."""
