"""The physics-backend seam (``sim/backend.py``): population batches and the CPU record."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.sim.backend import physics_record, robot_identity
from evomotion.studies import get_study


@pytest.mark.parametrize("name", ["humanoid-step", "humanoid-walk-open-loop",
                                  "humanoid-repertoire"])
def test_batches_of_rollouts_give_the_same_evaluation(name):
    """A population evaluated ``batch_rollouts`` at a time (here 2 or 3) equals the population
    evaluated at once, bit for bit: a rollout does not depend on its batch."""
    s = get_study(name)

    def evaluate(batch: int):
        cfg = resolve_config(s, None, [*s.smoke, f"problem.batch_rollouts={batch}"])
        seeded = getattr(cfg.problem, "with_run_seed", None)
        problem = s.make_problem(seeded(0) if seeded else cfg.problem)
        lo, hi = problem.genome.lower, problem.genome.upper
        genomes = lo + (hi - lo) * np.random.default_rng(1).random((5, lo.size))
        return problem.evaluate(genomes), problem

    whole, problem = evaluate(2048)
    parts, _ = evaluate(3)
    np.testing.assert_array_equal(whole.fitness, parts.fitness)
    for k in whole.metrics:
        np.testing.assert_array_equal(whole.metrics[k], parts.metrics[k], err_msg=k)
    assert len(whole) == 5
    rec = problem.physics_record()
    # the physics and the robot (the NAO's spec: its name and the SHA-256 of spec and MJCF)
    assert rec["backend"] == "cpu" and rec == {**physics_record(problem.sim),
                                               **robot_identity(problem.robot)}
    assert rec["robot"] == "nao" and len(rec["robot_mjcf_sha256"]) == 64
    assert problem.device_memory(100) is None  # host memory only


def test_batch_rollouts_sizes_the_memory_check():
    s = get_study("humanoid-step")
    small = resolve_config(s, None, ["algorithm.pop_size=8192", "problem.batch_rollouts=64"])
    big = resolve_config(s, None, ["algorithm.pop_size=8192", "problem.batch_rollouts=8192"])
    assert small.problem.memory_bytes(8192) * 128 == big.problem.memory_bytes(8192)
    with pytest.raises(InputError, match="problem.batch_rollouts"):
        resolve_config(s, None, ["problem.batch_rollouts=0"])
