"""The balance task as a policy-search problem (``evomotion run humanoid-balance``).

The robot (``problem.robot``: "" = the NAO, or any biped spec) starts standing in its nominal
pose (its spec pose in the stance of ``problem.stance_*``: :mod:`evomotion.sim.stance`); a
policy (:mod:`evomotion.core.policies`: linear as in ARS, a tanh MLP, or structured: a phase
tape plus feedback) reads its sensors every ``control_period_s`` (20 ms: 5 NAO physics
steps) and sets offsets (rad) from the nominal pose of its ``[evolve]`` joints, for
``duration_s`` = 10 s. Every episode is one perturbed world with a push of up to
``push_max_ns`` N s in a random horizontal direction (:mod:`.episodes`); a robot that falls
ends its episode.

An evaluation row is ``[params | obs mean | obs std | seed | episodes]``
(:mod:`evomotion.studies.policy_search`); the fitness (maximised) is the mean episode score
``up_fraction - tilt_weight * tilt_rad - action_weight * action_sq`` (:mod:`.episodes`), which is
also the metric ``return``; ``survived`` is the share of the row's episodes never fallen.
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

from evomotion.core.checks import check_choice, check_fields, check_number, check_text, inf_ok
from evomotion.core.problem import Evaluation, GenomeSpec, Sense
from evomotion.errors import InputError
from evomotion.sim.control_period import whole_steps
from evomotion.studies.humanoid_balance.episodes import (
    Episodes,
    WorldDraw,
    episode_world,
    push_range,
    run_episodes,
)
from evomotion.studies.policy_search import EpisodeRows, neutral_rows, split_rows
from evomotion.studies.policy_validation import check_validation

if TYPE_CHECKING:
    from evomotion.sim.warp_closed_loop import WarpClosedLoopSimulator

MAX_EPISODES = 1000
MAX_DURATION_S = 600.0
MAX_PUSH_NS = 1000.0
METRICS = ("return", "steps", "survived", "time_up_s", "tilt_rad", "action_sq")


@dataclass(frozen=True)
class HumanoidBalanceConfig:
    """``[problem]`` of humanoid-balance."""

    robot: str = ""  # "" or "nao": the NAO; another bundled biped (op3) or a spec .toml
    #: the stance it stands in, the policy's actions offsets from it (sim/stance.py; rad):
    #: feet wider apart, the left ahead of the right, lower; 0, 0, 0: the spec pose
    stance_width_rad: float = 0.3
    stance_stagger_rad: float = 0.2
    stance_crouch_rad: float = 0.15
    #: the torso pitched forward at the hips, the soles flat: the centre of mass over the
    #: middle of the support polygon along x (sim/stance.py; docs/humanoid-balance.md)
    stance_lean_rad: float = 0.0
    duration_s: float = 10.0  # episode length (s)
    control_period_s: float = 0.02  # the policy's period (s), a whole number of physics steps
    #: the observation channels (sim/observations.py), comma-separated
    observations: str = "joint_pos,joint_vel,gravity,gyro,foot_contact"
    policy: str = "linear"  # "linear" (ARS), "mlp" (tanh hidden layers) or "structured"
    harmonics: int = 2  # structured: sin/cos pairs of the phase tape per joint
    phase_period_s: float = 1.0  # the phase observation's clock period (s)
    hidden: int = 32  # MLP: units per hidden layer
    layers: int = 2  # MLP: hidden layers
    normalize: bool = True  # ARS V2 observation normalisation (false: V1)
    #: start the search from this exported policy (a policy.npz or a run folder holding one,
    #: of the same controller; "" the study's own start): studies/policy_start.py
    start_policy: str = ""
    #: validate the centre of every this many generations on validate_episodes fixed episodes
    #: and export the best validated one (0: export the best single evaluation; the
    #: winner's curse): studies/policy_validation.py
    validate_every: int = 0
    validate_episodes: int = 32
    action_scale: float = 0.3  # rad of joint offset per unit of policy output
    #: bound on every normalised observation (the standing robot's first statistics are
    #: tiny, so a push would otherwise drive the inputs to thousands); inf: none (ARS)
    clip_obs: float = inf_ok(5.0, "no clipping")
    episodes: int = 2  # training episodes (worlds) per individual and generation
    eval_episodes: int = 8  # episodes of the centre per generation (the reported return)
    push_min_ns: float = 2.0  # push magnitude U(min, max) N s on the NAO (scaled by mass)
    push_max_ns: float = 4.5
    push_window_start: float = 0.2  # push time U(start, end) x duration_s
    push_window_end: float = 0.6
    perturb: bool = True  # also draw friction, masses, CoM, motors, latency per episode
    tilt_weight: float = 0.1  # score lost per radian of mean torso tilt
    action_weight: float = 0.1  # score lost per rad^2 of mean squared action
    param_bound: float = 100.0  # the genome box +- this (the ES starts at 0: stand still)
    threads: int = 0  # mujoco.rollout threads; 0 = all cores (1 in a worker process)
    backend: str = "cpu"  # physics: cpu (mujoco.rollout, float64) | warp (MuJoCo Warp, float32)
    warp_device: str = ""  # backend warp: "cuda:0", "cpu", ...; "" = the first GPU, else the CPU
    warp_deterministic: bool = False  # backend warp: opt.deterministic (docs/gpu.md)

    def validate(self) -> None:
        check_fields(self, "problem")
        check_text("problem.robot", self.robot)
        check_text("problem.start_policy", self.start_policy)
        check_validation(self.validate_every, self.validate_episodes)
        for key in ("stance_width_rad", "stance_stagger_rad", "stance_crouch_rad",
                    "stance_lean_rad"):
            check_number(f"problem.{key}", getattr(self, key), lo=-1.0, hi=1.0)
        check_number("problem.duration_s", self.duration_s, lo=0.0, hi=MAX_DURATION_S,
                     lo_open=True)
        check_number("problem.control_period_s", self.control_period_s, lo=0.0, hi=1.0,
                     lo_open=True)
        check_choice("problem.policy", self.policy, ("linear", "mlp", "structured"))
        if self.policy == "structured" and "phase" not in self.channels():
            raise InputError("problem.policy: the structured policy needs the phase "
                             "observation: add phase to problem.observations")
        check_number("problem.harmonics", self.harmonics, lo=0, hi=64, integer=True)
        check_number("problem.phase_period_s", self.phase_period_s, lo=0.0, hi=MAX_DURATION_S,
                     lo_open=True)
        check_number("problem.hidden", self.hidden, lo=1, hi=4096, integer=True)
        check_number("problem.layers", self.layers, lo=1, hi=8, integer=True)
        check_number("problem.action_scale", self.action_scale, lo=0.0, hi=10.0, lo_open=True)
        for key in ("episodes", "eval_episodes"):
            check_number(f"problem.{key}", getattr(self, key), lo=1, hi=MAX_EPISODES,
                         integer=True)
        check_number("problem.push_min_ns", self.push_min_ns, lo=0.0, hi=MAX_PUSH_NS)
        check_number("problem.push_max_ns", self.push_max_ns, lo=self.push_min_ns,
                     hi=MAX_PUSH_NS)
        check_number("problem.push_window_start", self.push_window_start, lo=0.0, hi=1.0)
        check_number("problem.push_window_end", self.push_window_end,
                     lo=self.push_window_start, hi=1.0)
        for key in ("tilt_weight", "action_weight"):
            check_number(f"problem.{key}", getattr(self, key), lo=0.0, hi=1000.0)
        check_number("problem.clip_obs", self.clip_obs, lo=0.0, lo_open=True, allow_inf=True)
        check_number("problem.param_bound", self.param_bound, lo=1e-6, hi=1e6)
        check_number("problem.threads", self.threads, lo=0, hi=1024, integer=True)
        check_choice("problem.backend", self.backend, ("cpu", "warp"))
        check_text("problem.warp_device", self.warp_device)
        if not isinstance(self.warp_deterministic, bool):
            raise InputError("problem.warp_deterministic: expected true or false, got "
                             f"{self.warp_deterministic!r}")
        for key in ("normalize", "perturb"):
            if not isinstance(getattr(self, key), bool):
                raise InputError(f"problem.{key}: expected true or false, got "
                                 f"{getattr(self, key)!r}")

    def channels(self) -> tuple[str, ...]:
        return tuple(c.strip() for c in self.observations.split(",") if c.strip())

    def for_worker(self) -> HumanoidBalanceConfig:
        """One rollout thread in a one-core evaluator worker (an explicit count is kept)."""
        return replace(self, threads=1) if self.threads == 0 else self


class HumanoidBalanceProblem:
    """Rows of policy parameters (+ normaliser and seeds) -> balance scores."""

    sense: Sense = "max"
    metric_names: tuple[str, ...] = METRICS

    def __init__(self, cfg: HumanoidBalanceConfig | None = None) -> None:
        from evomotion.core.policies import make_policy
        from evomotion.sim.closed_loop import ClosedLoopSimulator
        from evomotion.sim.observations import ObservationSpec
        from evomotion.sim.robots import load_robot
        from evomotion.sim.stance import with_stance

        self.cfg = cfg = cfg or HumanoidBalanceConfig()
        cfg.validate()
        r = load_robot(cfg.robot or "nao")
        if len(r.feet) != 2:
            raise InputError(f"problem.robot: {r.name} has {len(r.feet)} feet; the balance "
                             "task stands a biped")
        self.robot = r = with_stance(r, cfg.stance_width_rad, cfg.stance_stagger_rad,
                                     cfg.stance_crouch_rad, "problem.stance_width_rad, "
                                     "stance_stagger_rad, stance_crouch_rad, stance_lean_rad",
                                     lean_rad=cfg.stance_lean_rad)
        self.dt = float(r.model.opt.timestep)
        k = whole_steps(cfg.control_period_s, self.dt)
        if k is None:
            raise InputError(f"problem.control_period_s: {cfg.control_period_s} s is not a whole "
                             f"number of {r.name}'s {self.dt} s physics steps")
        self.control_steps = k
        self.nstep = int(math.ceil(cfg.duration_s / self.dt))
        self.obs_spec = ObservationSpec(cfg.channels(), phase_period_s=cfg.phase_period_s)
        threads = cfg.threads or max(1, min(os.cpu_count() or 1, 8))
        self.sim: ClosedLoopSimulator | WarpClosedLoopSimulator
        if cfg.backend == "warp":  # the same loop on MuJoCo Warp (sim/warp_closed_loop.py)
            from evomotion.sim.warp_closed_loop import WarpClosedLoopSimulator

            self.sim = WarpClosedLoopSimulator(r, self.obs_spec, self.control_steps,
                                               device=cfg.warp_device,
                                               deterministic=cfg.warp_deterministic)
        else:
            self.sim = ClosedLoopSimulator(r, self.obs_spec, self.control_steps, threads)
        self.obs_names = self.sim.observe.names
        self.obs_dim, self.act_dim = self.sim.observation_size, self.sim.action_size
        nominal = np.asarray(r.pose, float)[self.sim.columns]
        low, high = self.sim.lower - nominal, self.sim.upper - nominal
        options: dict[str, Any] = ({"hidden": (cfg.hidden,) * cfg.layers}
                                   if cfg.policy == "mlp" else {})
        if cfg.policy == "structured":
            names = list(self.obs_names)
            options = {"harmonics": cfg.harmonics,
                       "phase_columns": (names.index("phase:sin"), names.index("phase:cos"))}
        self.policy = make_policy(cfg.policy, self.obs_dim, self.act_dim,
                                  scale=cfg.action_scale, low=low, high=high,
                                  clip_obs=cfg.clip_obs, **options)
        lo, hi = self.policy.genome_bounds(cfg.param_bound)
        self.genome = GenomeSpec(lo, hi)
        self.draw = WorldDraw(push_range(r, cfg.push_min_ns, cfg.push_max_ns),
                              (cfg.push_window_start, cfg.push_window_end), cfg.duration_s,
                              cfg.perturb)
        self.episodes, self.eval_episodes = cfg.episodes, cfg.eval_episodes
        self.normalize = cfg.normalize

    def physics_record(self) -> dict[str, Any]:
        """``physics.json``: the backend and what it guarantees (a GPU run is not
        bit-identical; docs/gpu.md), the robot and the digests of its spec and MJCF."""
        from evomotion.sim.backend import physics_record

        return physics_record(self.sim, self.robot)

    def worlds(self, seeds: np.ndarray, push_ns: float | None = None) -> list:
        """The episode worlds of ``seeds`` (one drawn per distinct seed)."""
        cache: dict[int, Any] = {}
        for s in np.unique(seeds):
            cache[int(s)] = episode_world(self.robot.model, self.draw, int(s), push_ns)
        return [cache[int(s)] for s in seeds]

    def play(self, params: np.ndarray, mean: np.ndarray, std: np.ndarray, seeds: np.ndarray,
             push_ns: float | None = None, record_states: bool = False) -> Episodes:
        """Episodes of ``params[n, P]`` (normalisers ``mean[n, o]``, ``std[n, o]``) in the
        worlds of ``seeds[n]``."""
        return run_episodes(self.sim, self.policy, np.asarray(params, float),
                            np.asarray(mean, float), np.asarray(std, float),
                            self.worlds(np.asarray(seeds), push_ns), self.nstep,
                            self.cfg.tilt_weight, self.cfg.action_weight, record_states)

    def evaluation_rows(self, genomes: np.ndarray) -> np.ndarray:
        """``genomes`` as rows with no normalisation and the episodes from seed 0."""
        return neutral_rows(genomes, self.obs_dim, self.episodes)

    def evaluate(self, rows: np.ndarray) -> Evaluation:
        params, mean, std, seeds, episodes = split_rows(np.asarray(rows, float),
                                                        self.genome.dim, self.obs_dim)
        eps = EpisodeRows.of(seeds, episodes, MAX_EPISODES)
        o = eps.owner
        ep = self.play(params[o], mean[o], std[o], eps.seeds)
        avg = eps.mean
        ret = avg(ep.score)
        control_steps = np.ceil(ep.result.steps / self.control_steps)
        return Evaluation(ret, {"return": ret, "steps": avg(control_steps),
                                "survived": avg(ep.survived), "time_up_s": avg(ep.time_up_s),
                                "tilt_rad": avg(ep.tilt_rad), "action_sq": avg(ep.action_sq),
                                **eps.moments(ep.obs_count, ep.obs_mean, ep.obs_m2)})
