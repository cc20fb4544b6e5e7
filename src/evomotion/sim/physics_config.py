"""The physics keys of the MuJoCo studies' ``[problem]`` section, defined once.

Two typed frozen dataclasses that a study's problem config inherits, so that its
``[problem]`` section keeps the flat keys users write (``problem.backend = "warp"``,
``problem.worlds = 3``) and old run folders' ``config.toml`` load and resume unchanged:

- :class:`PhysicsConfig`: how the rollouts are simulated (the backend of
  :mod:`evomotion.sim.backend`, its threads or GPU, the batch size, the early stop of fallen
  robots);
- :class:`PerturbedWorldsConfig`: the K worlds every candidate is evaluated in
  (:mod:`evomotion.sim.worlds`) and how their fitness values are combined.

:func:`validate_physics` checks both in one place (one :class:`~evomotion.errors.InputError`
line naming the key). A study lists its own keys in a dataclass that comes *last* among the
bases, e.g. ``class HumanoidStepConfig(PhysicsConfig, PerturbedWorldsConfig, StepKeys)``:
dataclass fields are collected in reverse method resolution order (Python reference,
``dataclasses``, "Inheritance"), so the study's keys come first in ``config.toml`` and the
studio's form, then the worlds, then the physics, then the config's own fields (a field
redeclared there, e.g. another ``segment_s`` default, keeps its place).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Self

from evomotion.core.checks import check_choice, check_number
from evomotion.errors import InputError

#: ``backend``: MuJoCo's C engine in ``mujoco.rollout`` threads (float64) or MuJoCo Warp (float32)
BACKENDS = ("cpu", "warp")
#: ``world_aggregate``: the mean of the K fitness values or their ``world_quantile``
WORLD_AGGREGATES = ("mean", "quantile")
#: the documented ranges: ``threads`` (one ``MjData`` each), ``worlds`` (K rollouts per
#: candidate), ``warp_nconmax`` (contacts per world), ``batch_rollouts``, ``segment_s`` (s)
MAX_THREADS = 1024
MAX_WORLDS = 1024
MAX_WARP_NCONMAX = 4096
MAX_BATCH_ROLLOUTS = 2**20
MAX_SEGMENT_S = 60.0


@dataclass(frozen=True)
class PhysicsConfig:
    """How a study's rollouts are simulated (:func:`evomotion.sim.backend.make_simulator`).
    Results are bit-identical for one seed whatever ``threads`` and ``batch_rollouts`` (on the
    ``cpu`` backend); ``segment_s`` only saves time (a fallen robot's remaining states repeat
    its fallen state, which the fitness never reads past the fall)."""

    threads: int = 0  # mujoco.rollout threads, [0, 1024]; 0 = all cores
    backend: str = "cpu"  # physics: cpu (mujoco.rollout, float64) | warp (MuJoCo Warp, float32)
    warp_device: str = ""  # backend warp: "cuda:0", "cpu", ...; "" = the first GPU, else the CPU
    # backend warp: MuJoCo Warp opt.deterministic = ALL; off by default: on an H200 it ran
    # 7.5x slower and still not bit-identical with mujoco-warp 4.0.0 (docs/gpu.md)
    warp_deterministic: bool = False
    warp_nconmax: int = 16  # backend warp: contacts per world to start with, [1, 4096] (grown)
    batch_rollouts: int = 2048  # rollouts simulated (and recorded in memory) at once, [1, 2^20]
    segment_s: float = 0.4  # fallen robots stop being simulated at these boundaries, (0, 60] s

    def for_worker(self) -> Self:
        """The config of a one-core evaluator worker: ``threads`` 0 (all cores) becomes 1;
        an explicit thread count is kept."""
        return dataclasses.replace(self, threads=1) if self.threads == 0 else self


@dataclass(frozen=True)
class PerturbedWorldsConfig:
    """The K worlds each candidate is evaluated in: the nominal one and K - 1 drawn by
    :func:`evomotion.sim.worlds.draw_worlds` from ``numpy.random.default_rng(world_seed)``;
    its fitness combines the K values (:func:`evomotion.sim.worlds.aggregate_worlds`)."""

    worlds: int = 1  # K worlds per candidate, [1, 1024]: the nominal one and K - 1 perturbed
    world_seed: int = -1  # the K worlds come from default_rng(world_seed); -1: the run's seed
    world_aggregate: str = "mean"  # mean | quantile: how the K fitness values are combined
    world_quantile: float = 0.25  # with "quantile": this quantile of the K values, [0, 1]

    def with_run_seed(self, seed: int) -> Self:
        """The config a run with ``run.seed = seed`` uses: ``world_seed`` -1 becomes ``seed``, so
        the K perturbed worlds are drawn from the run seed unless a seed of their own is set."""
        return dataclasses.replace(self, world_seed=seed) if self.world_seed < 0 else self


def validate_physics(cfg: Any, section: str = "problem") -> None:
    """One-line :class:`InputError` for a bad physics key of ``cfg``: the fields of
    :class:`PhysicsConfig`, and of :class:`PerturbedWorldsConfig` when ``cfg`` is one, each
    within its documented range (the constants above)."""
    if isinstance(cfg, PerturbedWorldsConfig):
        check_choice(f"{section}.world_aggregate", cfg.world_aggregate, WORLD_AGGREGATES)
        check_number(f"{section}.worlds", cfg.worlds, lo=1, hi=MAX_WORLDS, integer=True)
        check_number(f"{section}.world_seed", cfg.world_seed, lo=-1, integer=True)
        check_number(f"{section}.world_quantile", cfg.world_quantile, lo=0.0, hi=1.0)
    check_number(f"{section}.threads", cfg.threads, lo=0, hi=MAX_THREADS, integer=True)
    check_choice(f"{section}.backend", cfg.backend, BACKENDS)
    check_number(f"{section}.warp_nconmax", cfg.warp_nconmax, lo=1, hi=MAX_WARP_NCONMAX,
                 integer=True)
    check_number(f"{section}.batch_rollouts", cfg.batch_rollouts, lo=1, hi=MAX_BATCH_ROLLOUTS,
                 integer=True)
    if not isinstance(cfg.warp_device, str):
        raise InputError(f"{section}.warp_device: expected a device name such as 'cuda:0' or "
                         f"'cpu' ('' = the first GPU, else the CPU), got {cfg.warp_device!r}")
    if not isinstance(cfg.warp_deterministic, bool):
        raise InputError(f"{section}.warp_deterministic: expected true or false, got "
                         f"{cfg.warp_deterministic!r}")
    check_number(f"{section}.segment_s", cfg.segment_s, lo=0.0, hi=MAX_SEGMENT_S, lo_open=True)
