"""Physics backends behind one simulator interface: ``problem.backend = "cpu" | "warp"`` (the
keys and their checks: :mod:`evomotion.sim.physics_config`).

- ``cpu`` (default): :class:`~evomotion.sim.rollout.BatchSimulator`, MuJoCo's C engine in
  ``mujoco.rollout`` threads, float64, bit-identical for one seed whatever the evaluator;
- ``warp``: :class:`~evomotion.sim.warp_rollout.WarpSimulator`, MuJoCo Warp stepping the
  whole population as one batch on a CUDA GPU (``warp_device = ""`` picks the first GPU,
  else Warp's CPU device), float32. Optional extra ``[gpu]`` (``mujoco-warp``).

Why MuJoCo Warp and not MJX: it runs the same MJCF with this model's features (implicitfast
integrator, Newton solver, pyramidal cones, box/capsule/sphere/plane contacts, touch and force
sensors) from the same ``MjModel``, scales better than MJX's JAX implementation on
contact-rich scenes (MuJoCo docs, "When to use MJWarp"), needs no JAX, has batched model
fields for perturbed worlds, and its version follows MuJoCo's (mujoco-warp 4.0.0 with
mujoco 4.0.0). On a GPU it does not promise bit-identical runs (contacts are placed with
atomics; 4.0.0's deterministic contact sort is a stub): ``physics.json`` records what holds,
docs/gpu.md says which guarantees change.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import mujoco

from evomotion.errors import InputError


def make_simulator(model: mujoco.MjModel, cfg: Any, threads: int = 0):
    """The simulator ``cfg.backend`` names for ``model`` (``threads``: CPU threads)."""
    if getattr(cfg, "backend", "cpu") == "warp":
        from evomotion.sim.warp_rollout import WarpSimulator

        return WarpSimulator(model, cfg.warp_device, cfg.warp_deterministic, cfg.warp_nconmax)
    from evomotion.sim.rollout import BatchSimulator

    return BatchSimulator(model, threads)


def physics_record(sim: Any, robot: Any = None) -> dict[str, Any]:
    """What a run folder records about its physics (``physics.json``): the backend, its
    device and guarantee, the host's numpy, SIMD features and BLAS kernels
    (:func:`~evomotion.sim.cpu_platform.cpu_platform`); with ``robot`` also its name and the
    digests of its spec and MJCF (:func:`robot_identity`)."""
    from evomotion.sim.cpu_platform import cpu_platform

    if getattr(sim, "backend", "cpu") == "warp":
        record = sim.record()
    else:
        record = {"backend": "cpu", "threads": sim.nthread, "precision": "float64",
                  "mujoco": mujoco.__version__,
                  "guarantee": "bit-identical for one seed, whatever the evaluator and thread "
                               "count, on machines with the same numpy, numpy_simd and blas "
                               "(sim/cpu_platform.py)"}
    record.update(cpu_platform())
    if robot is not None:
        record.update(robot_identity(robot))
    return record


def robot_identity(robot: Any) -> dict[str, str]:
    """Name and SHA-256 digests of a robot's spec file and MJCF file (the MJCF's bytes as
    the robot was built from them; the spec read again, bounded: ``"?"`` when it cannot be)."""
    import hashlib

    from evomotion.sim.robots.spec import MAX_SPEC_BYTES
    from evomotion.textio import read_file_bytes

    try:
        spec_digest = hashlib.sha256(read_file_bytes(robot.spec.path, "robot spec",
                                                     MAX_SPEC_BYTES)).hexdigest()
    except InputError:
        spec_digest = "?"
    return {"robot": robot.name, "robot_spec": str(robot.spec.path.resolve()),
            "robot_spec_sha256": spec_digest,
            "robot_mjcf_sha256": getattr(robot, "mjcf_sha256", "") or "?"}


def device_memory(sim: Any, batch: int, nstep: int) -> tuple[int, int | None, str] | None:
    """(needed bytes, free bytes, device) of a batch on the simulator's device, or ``None``
    for the CPU backend (its memory is the host's, in the problem's ``memory_bytes``)."""
    if getattr(sim, "backend", "cpu") != "warp":
        return None
    est = sim.memory(batch, nstep)
    return est.needed, est.free, est.device


def in_batches(evaluate, genomes, per_batch: int):
    """``evaluate(genomes)`` on consecutive slices of at most ``per_batch`` genomes, joined
    (:meth:`~evomotion.core.problem.Evaluation.concat`): a population larger than
    ``problem.batch_rollouts`` is simulated batch by batch, so the recorded trajectories of one
    batch are what must fit in memory. A rollout does not depend on its batch, so the result
    is the same."""
    from evomotion.core.problem import Evaluation

    n, size = len(genomes), max(int(per_batch), 1)
    if n <= size:
        return evaluate(genomes)
    return Evaluation.concat([evaluate(genomes[i:i + size]) for i in range(0, n, size)])


class BatchedRollouts:
    """Mixin of the MuJoCo problems: ``evaluate`` in batches of ``cfg.batch_rollouts``
    rollouts (:func:`in_batches`), the run folder's ``physics_record`` and the GPU
    ``device_memory`` check. The problem has ``sim``, ``cfg.batch_rollouts``,
    ``segment_steps``, ``worlds`` (``None`` or the K perturbed worlds, K rollouts per genome)
    and ``_evaluate_batch(genomes)``."""

    worlds: list | None = None
    sim: Any
    cfg: Any
    segment_steps: int
    _evaluate_batch: Callable[[Any], Any]

    def _rollouts_per_genome(self) -> int:
        return len(self.worlds) if self.worlds else 1

    def physics_record(self) -> dict[str, Any]:
        """The physics backend, device and its reproducibility guarantee (``physics.json``);
        for another robot than the NAO also its name and the SHA-256 of its spec and MJCF (a
        resume with an edited robot is noted in the log)."""
        return physics_record(self.sim, getattr(self, "robot", None))

    def device_memory(self, pop_size: int) -> tuple[int, int | None, str] | None:
        """(needed, free bytes, device) of a population's batch on a GPU backend, else None."""
        rollouts = min(pop_size * self._rollouts_per_genome(), self.cfg.batch_rollouts)
        return device_memory(self.sim, rollouts, self.segment_steps)

    def evaluate(self, genomes):
        """Fitness and metrics of a batch, ``problem.batch_rollouts`` rollouts at a time."""
        import numpy as np

        genomes = np.atleast_2d(np.asarray(genomes, dtype=float))
        per = max(self.cfg.batch_rollouts // self._rollouts_per_genome(), 1)
        return in_batches(self._evaluate_batch, genomes, per)
