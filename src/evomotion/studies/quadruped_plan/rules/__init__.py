"""The walking problem's rules: the robot model, its moves (shifts, steps), the evaluation
functions and heuristics, and the compiled successors (``_walkcore``)."""
