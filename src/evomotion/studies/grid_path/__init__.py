"""Grid path planning with a cellular GA (paper 004): maps, exact geometry and solvers, the
paper's perpendicular encoding, operators, repair, run driver and study commands."""
