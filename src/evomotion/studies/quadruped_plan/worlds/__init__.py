"""The worlds the robot walks in: world files (the bundled ``*.world`` lie here), terrain,
geometry, world checks and coarse routes."""
