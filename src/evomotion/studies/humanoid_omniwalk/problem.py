"""The omnidirectional walk controller as a policy-search problem
(``evomotion run humanoid-walk``).

The controller (:mod:`.controller`) is a structured policy: a phase tape modulated by the
command ``(vx, vy, ω)`` (fitted by least squares to the walk engine of :mod:`.omni_gait`, where
the search starts) plus linear feedback from the NAO's sensors (joint angles and velocities,
the IMU's gravity direction and gyro, the feet's contacts, the command); it sets 15 joints
every ``control_period_s`` (the legs, the hip yaw-pitch motor once, the shoulders). Another
biped (``robot``: the OP3, the dm humanoid, a spec ``.toml``) gets the same controller on its
legs, fitted to the engine solved by its numerical leg IK (:mod:`.ik_gait`).

Every episode (``duration_s``) is one perturbed world (:mod:`evomotion.studies.episode_worlds`:
friction, masses, CoM, motors, latency, one push up to ``push_max_ns``) and one random command
schedule (:mod:`.commands`: a new command every 2-4 s). The episode score (maximised):

    score = mean_c [alive_c (r_v + yaw_share r_ω) / (1 + yaw_share)]
            − energy_weight · power_w − speed_weight · speed_excess − fall_weight · fell

``r_v = exp(−|v − v_cmd|² / σ_v²)``, ``r_ω = exp(−(ω − ω_cmd)² / σ_ω²)`` over sliding one-cycle
windows (:func:`.commands.tracking`, after the first cycle), ``alive_c`` 0 from the fall on (a
fall loses the rest of the episode); ``power_w`` the servos' mean mechanical power
``Σ|τ q̇|`` (W, ``τ = clip(kp (target − q), force range)``, sampled at the control steps);
``speed_excess`` the mean over control steps of ``Σ_j max(|Δtarget_j| / Δt / v_j − 1, 0)``,
``v_j`` the NAO motor's no-load speed (:data:`~evomotion.sim.robots.nao.joint_limits.
SPEED_LIMITS`): targets faster than the real motors cost; ``fell`` 1 for an episode that fell
(``fall_weight`` 0 by default: the fall costs only the windows it loses).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass, replace

import numpy as np

from evomotion.core.checks import check_fields, check_number, check_text, inf_ok
from evomotion.core.policies.mirror import with_mirror_image
from evomotion.core.problem import Evaluation, GenomeSpec, Sense
from evomotion.errors import InputError
from evomotion.studies.episode_worlds import WorldDraw, episode_world, push_range
from evomotion.studies.humanoid_omniwalk.commands import (
    KIND_WEIGHTS,
    CommandDraw,
    schedules,
    tracking,
)
from evomotion.studies.humanoid_omniwalk.omni_gait import OmniGait
from evomotion.studies.policy_search import (
    EpisodeRows,
    neutral_rows,
    observation_moments,
    split_rows,
)
from evomotion.studies.policy_validation import check_validation

MAX_EPISODES = 1000
METRICS = ("return", "steps", "survived", "time_up_s", "speed_error_mps",
           "yaw_rate_error_rps", "power_w", "speed_excess")


@dataclass(frozen=True)
class OmniWalkConfig:
    """``[problem]`` of humanoid-walk (SI units)."""

    robot: str = ""  # "" or "nao": the NAO; another bundled biped (op3, dm-humanoid) or a spec
    duration_s: float = 8.0  # episode length (s)
    control_period_s: float = 0.02  # the controller's period (s)
    harmonics: int = 3  # sin/cos pairs of the phase tape
    clip_obs: float = inf_ok(5.0, "no clipping")  # bound on every normalised observation
    #: the tape reads the command plus gains on the observation (longer/wider steps the way
    #: the torso leans: capture-style step adjustment; core/policies/structured.py)
    #: (the study's default turns it on, with command_feedback_start 0.1: study.py; false
    #: here is what a run folder from before these keys meant)
    command_feedback: bool = False
    #: with command_feedback, the search's start for G's gain of vx on the normalised IMU
    #: gravity:x (forward lean); 0.1 ~ 1 m/s per unit of gravity direction on this walk, whose
    #: gravity-x std is about 0.1 (benchmarks/command_feedback_probe.py's k_x = 1)
    command_feedback_start: float = 0.0
    #: a mirror-symmetric controller: the search runs on the parameters of controllers that
    #: act as their own mirror image (about half; core/policies/mirror.py); the NAO only
    symmetric: bool = False
    #: capture-point foot placement from leg odometry on top of the controller, the swing
    #: foot moved by this times the capture point's offset (capture_step.py); 0 off; the NAO
    capture_gain: float = 0.0
    normalize: bool = True  # ARS V2 observation normalisation
    #: start the search from this exported policy (a policy.npz or a run folder holding one,
    #: of the same controller; "" the study's own start): studies/policy_start.py
    start_policy: str = ""
    #: validate the centre of every this many generations on validate_episodes fixed episodes
    #: and export the best validated one (0: export the best single evaluation; the
    #: winner's curse): studies/policy_validation.py
    validate_every: int = 0
    validate_episodes: int = 32
    episodes: int = 1  # training episodes per individual and generation
    eval_episodes: int = 8  # episodes of the centre per generation (the reported return)
    vx_min: float = -0.2  # command ranges (m/s, rad/s); see commands.py
    vx_max: float = 0.45
    vy_max: float = 0.2
    yaw_rate_max: float = 1.2
    #: the command kinds' weights: forward/backward, sideways, turning, mixed, standing
    #: (commands.py; normalised to sum 1); e.g. [1, 0, 0, 0, 0]: forward/backward only
    command_weights: tuple[float, ...] = KIND_WEIGHTS
    hold_min_s: float = 2.0  # a new command every U(hold_min_s, hold_max_s) s
    hold_max_s: float = 4.0
    ramp_s: float = 0.5  # commands ramp linearly over this (s)
    push_min_ns: float = 0.0  # push magnitude U(min, max) N s, random direction
    push_max_ns: float = 5.0
    perturb: bool = True  # friction, masses, CoM, motors, latency per episode
    sigma_v_mps: float = 0.1  # tracking kernel widths
    sigma_yaw_rps: float = 0.3
    yaw_share: float = 0.5  # weight of yaw tracking beside velocity tracking
    energy_weight: float = 0.0005  # score lost per W of mean servo power
    speed_weight: float = 0.5  # score lost per unit of speed excess
    fall_weight: float = 0.0  # score lost by an episode that falls (beside the lost windows)
    param_bound: float = 100.0  # the genome box +- this
    threads: int = 0  # mujoco.rollout threads; 0 = all cores (1 in a worker process)
    # the walk engine the tape starts from (omni_gait.py), in the NAO's units: another robot
    # takes them scaled to its leg (ik_gait.py)
    period_s: float = 0.48
    swing_fraction: float = 0.45
    step_height_m: float = 0.02
    leg_height_m: float = 0.155
    width_m: float = 0.03
    sway_m: float = 0.025
    sway_phase_rad: float = 0.0  # ψ_s (omni_gait.py; the other robots' engine: ik_gait.py)
    lean_rad: float = 0.05

    def validate(self) -> None:
        check_fields(self, "problem")
        check_text("problem.robot", self.robot)
        check_text("problem.start_policy", self.start_policy)
        check_validation(self.validate_every, self.validate_episodes)
        check_number("problem.duration_s", self.duration_s, lo=0.0, hi=600.0, lo_open=True)
        check_number("problem.control_period_s", self.control_period_s, lo=0.0, hi=1.0,
                     lo_open=True)
        check_number("problem.harmonics", self.harmonics, lo=1, hi=16, integer=True)
        check_number("problem.command_feedback_start", self.command_feedback_start, lo=-1.0,
                     hi=1.0)
        check_number("problem.clip_obs", self.clip_obs, lo=0.0, lo_open=True, allow_inf=True)
        for key in ("episodes", "eval_episodes"):
            check_number(f"problem.{key}", getattr(self, key), lo=1, hi=MAX_EPISODES,
                         integer=True)
        check_number("problem.vx_max", self.vx_max, lo=0.0, hi=2.0)
        check_number("problem.vx_min", self.vx_min, lo=-2.0, hi=self.vx_max)
        if len(self.command_weights) != len(KIND_WEIGHTS):
            raise InputError(f"problem.command_weights: expected {len(KIND_WEIGHTS)} weights "
                             "(forward/backward, sideways, turning, mixed, standing), got "
                             f"{len(self.command_weights)}")
        for i, wt in enumerate(self.command_weights):
            check_number(f"problem.command_weights[{i}]", wt, lo=0.0, hi=1000.0)
        if sum(self.command_weights) <= 0:
            raise InputError("problem.command_weights: expected at least one weight above 0")
        check_number("problem.vy_max", self.vy_max, lo=0.0, hi=2.0)
        check_number("problem.yaw_rate_max", self.yaw_rate_max, lo=0.0, hi=10.0)
        check_number("problem.hold_min_s", self.hold_min_s, lo=0.0, hi=600.0, lo_open=True)
        check_number("problem.hold_max_s", self.hold_max_s, lo=self.hold_min_s, hi=600.0)
        check_number("problem.ramp_s", self.ramp_s, lo=0.0, hi=60.0, lo_open=True)
        check_number("problem.push_min_ns", self.push_min_ns, lo=0.0, hi=1000.0)
        check_number("problem.push_max_ns", self.push_max_ns, lo=self.push_min_ns, hi=1000.0)
        for key in ("sigma_v_mps", "sigma_yaw_rps"):
            check_number(f"problem.{key}", getattr(self, key), lo=0.0, hi=100.0, lo_open=True)
        for key in ("yaw_share", "energy_weight", "speed_weight", "fall_weight"):
            check_number(f"problem.{key}", getattr(self, key), lo=0.0, hi=1000.0)
        check_number("problem.capture_gain", self.capture_gain, lo=0.0, hi=3.0)
        check_number("problem.param_bound", self.param_bound, lo=1e-6, hi=1e6)
        check_number("problem.threads", self.threads, lo=0, hi=1024, integer=True)
        check_number("problem.period_s", self.period_s, lo=0.2, hi=1.5)
        check_number("problem.swing_fraction", self.swing_fraction, lo=0.2, hi=0.5)
        check_number("problem.step_height_m", self.step_height_m, lo=0.0, hi=0.06)
        check_number("problem.leg_height_m", self.leg_height_m, lo=0.12, hi=0.2)
        check_number("problem.width_m", self.width_m, lo=-0.01, hi=0.06)
        check_number("problem.sway_m", self.sway_m, lo=0.0, hi=0.06)
        check_number("problem.lean_rad", self.lean_rad, lo=-0.2, hi=0.4)
        check_number("problem.sway_phase_rad", self.sway_phase_rad, lo=-math.pi, hi=math.pi)
        for key in ("normalize", "perturb", "command_feedback", "symmetric"):
            if not isinstance(getattr(self, key), bool):
                raise InputError(f"problem.{key}: expected true or false, got "
                                 f"{getattr(self, key)!r}")

    def gait(self) -> OmniGait:
        return OmniGait(period_s=self.period_s, swing_fraction=self.swing_fraction,
                        step_height_m=self.step_height_m, leg_height_m=self.leg_height_m,
                        width_m=self.width_m, sway_m=self.sway_m, lean_rad=self.lean_rad,
                        sway_phase_rad=self.sway_phase_rad)

    def commands(self) -> CommandDraw:
        given = tuple(float(w) for w in self.command_weights)
        total = sum(given)
        weights = KIND_WEIGHTS if given == KIND_WEIGHTS else \
            tuple(w / total for w in given)  # the default drawn exactly as before
        return CommandDraw(self.vx_min, self.vx_max, self.vy_max, self.yaw_rate_max,
                           self.hold_min_s, self.hold_max_s, self.ramp_s, weights)

    def for_worker(self) -> OmniWalkConfig:
        """One rollout thread in a one-core evaluator worker (an explicit count is kept)."""
        return replace(self, threads=1) if self.threads == 0 else self


class OmniWalkProblem:
    """Rows of controller parameters (+ normaliser and seeds) -> walk scores."""

    sense: Sense = "max"
    metric_names: tuple[str, ...] = METRICS

    def __init__(self, cfg: OmniWalkConfig | None = None) -> None:
        from evomotion.studies.humanoid_omniwalk.controller import Controller

        self.cfg = cfg = cfg or OmniWalkConfig()
        cfg.validate()
        threads = cfg.threads or max(1, min(os.cpu_count() or 1, 8))
        self.ctl = ctl = Controller(cfg.gait(), cfg.control_period_s, cfg.harmonics,
                                    cfg.clip_obs, threads, cfg.command_feedback,
                                    cfg.command_feedback_start, cfg.robot, cfg.symmetric,
                                    cfg.capture_gain)
        self.robot, self.sim, self.policy = ctl.robot, ctl.sim, ctl.policy
        self.obs_spec, self.obs_names = ctl.obs_spec, ctl.sim.observe.names
        self.obs_dim, self.act_dim = self.sim.observation_size, self.sim.action_size
        self.control_steps, self.dt = ctl.sim.k, ctl.dt
        self.nstep = int(math.ceil(cfg.duration_s / self.dt))
        self.mirror = ctl.mirror
        lo, hi = self.policy.genome_bounds(cfg.param_bound)
        if self.mirror is not None:  # the box on the free numbers of a symmetric controller
            lo, hi = lo[:self.mirror.basis.dim], hi[:self.mirror.basis.dim]
        self.genome = GenomeSpec(lo, hi)
        self.draw = WorldDraw(push_range(self.robot, cfg.push_min_ns, cfg.push_max_ns),
                              (0.2, 0.8), cfg.duration_s, cfg.perturb)
        self.command_draw = cfg.commands()
        self.episodes, self.eval_episodes = cfg.episodes, cfg.eval_episodes
        self.normalize = cfg.normalize

    def initial_population(self, n: int | None, rng: np.random.Generator) -> np.ndarray:
        """The fitted walk engine (feedback gains 0): where the search starts (a symmetric
        controller: the symmetric tape nearest it)."""
        x = self.ctl.initial_params()
        return (x if self.mirror is None else self.mirror.basis.reduce(x))[None]

    def policy_params(self, genomes: np.ndarray) -> np.ndarray:
        """The controller parameters (``policy``'s) of ``genomes`` (the search's numbers)."""
        g = np.asarray(genomes, dtype=np.float64)
        return g if self.mirror is None else self.mirror.basis.expand(g)

    def physics_record(self) -> dict:
        """``physics.json``: the backend, what it guarantees and the host it holds on
        (:func:`evomotion.sim.backend.physics_record`), the robot and its digests."""
        from evomotion.sim.backend import physics_record

        return physics_record(self.sim, self.robot)

    def worlds(self, seeds: np.ndarray, push_ns: float | None = None) -> list:
        cache = {int(s): episode_world(self.robot.model, self.draw, int(s), push_ns)
                 for s in np.unique(seeds)}
        return [cache[int(s)] for s in seeds]

    def play(self, params, mean, std, seeds, push_ns: float | None = None,
             commands: np.ndarray | None = None):
        """Episodes of ``params[n, P]`` in the worlds and command schedules of ``seeds[n]``
        (or the given ``commands[n, C, 3]``): ``(metrics dict, ClosedLoopResult, commands)``."""
        seeds = np.asarray(seeds)
        C = math.ceil(self.nstep / self.control_steps)
        if commands is None:
            commands = schedules(self.command_draw, seeds, np.arange(C) * self.ctl.control_dt)
        res = self.ctl.run(np.asarray(params, float), np.asarray(mean, float),
                           np.asarray(std, float), self.worlds(seeds, push_ns), self.nstep,
                           commands)
        return self.score(res, commands), res, commands

    def score(self, res, commands: np.ndarray) -> dict[str, np.ndarray]:
        cfg = self.cfg
        W = self.ctl.window
        tr = tracking(res.torso, commands, W, self.ctl.control_dt)
        ev, ew = tr.errors()
        ends = np.arange(W, commands.shape[1] + 1)  # window ends (control steps)
        alive = ends[None] * self.control_steps <= res.fall_step[:, None]
        r = (np.exp(-(ev / cfg.sigma_v_mps) ** 2)
             + cfg.yaw_share * np.exp(-(ew / cfg.sigma_yaw_rps) ** 2)) / (1 + cfg.yaw_share)
        track = (r * alive).mean(axis=1)
        n_alive = np.maximum(alive.sum(axis=1), 1)
        power, excess = self.ctl.effort(res)
        score = (track - cfg.energy_weight * power - cfg.speed_weight * excess
                 - cfg.fall_weight * res.fell)
        return {"return": score, "survived": (~res.fell).astype(float),
                "time_up_s": res.fall_time_s, "steps": np.ceil(res.steps / self.control_steps),
                "speed_error_mps": (ev * alive).sum(axis=1) / n_alive,
                "yaw_rate_error_rps": (ew * alive).sum(axis=1) / n_alive,
                "power_w": power, "speed_excess": excess}

    def evaluation_rows(self, genomes: np.ndarray) -> np.ndarray:
        return neutral_rows(genomes, self.obs_dim, self.episodes)

    def evaluate(self, rows: np.ndarray) -> Evaluation:
        params, mean, std, seeds, episodes = split_rows(np.asarray(rows, float),
                                                        self.genome.dim, self.obs_dim)
        eps = EpisodeRows.of(seeds, episodes, MAX_EPISODES)
        o = eps.owner
        m, res, _ = self.play(self.policy_params(params)[o], mean[o], std[o], eps.seeds)
        count, obs_mean, obs_m2 = observation_moments(res.obs_count, res.obs_sum,
                                                      res.obs_sumsq)
        if self.mirror is not None:  # the normaliser sees each episode and its mirror image
            count, obs_mean, obs_m2 = with_mirror_image(count, obs_mean, obs_m2,
                                                        self.mirror.observation)
        avg = {k: eps.mean(v) for k, v in m.items()}
        return Evaluation(avg["return"], {**avg, **eps.moments(count, obs_mean, obs_m2)})
