"""Plans and their search: the plan document and checker, the planners (A*, weighted A*,
anytime), the search driver and state, simulation, and the planning experiment."""
