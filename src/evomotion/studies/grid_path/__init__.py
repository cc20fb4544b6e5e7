"""Grid path planning with a cellular GA (seed 004): maps, exact geometry and solvers, the
seed's perpendicular encoding, operators, repair, run driver and study commands."""
