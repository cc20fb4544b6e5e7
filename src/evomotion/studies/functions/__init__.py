"""Classic continuous benchmark functions (sphere, Rosenbrock, Rastrigin, Ackley)."""
