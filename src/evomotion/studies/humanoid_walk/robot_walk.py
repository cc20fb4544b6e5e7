"""The walk problem on another robot (``problem.robot``): the joint-space gait of
:mod:`.robot_gait` on a robot of :mod:`evomotion.sim.robot`, scored like the NAO walk.

Fitness (maximised), as :class:`~.problem.HumanoidWalkProblem`'s without the NAO's motor
speed check: fell: ``time_up_s + 0.1 clip(forward_m, -0.5, 0.5)``; stayed up: ``horizon_s +
1 + soft_floor(quality_m)`` with ``quality_m = forward_m - heading_weight |heading| -
lateral_weight |lateral_m| - excess_weight max(|heading| - tolerance forward_m, 0) -
energy_weight cost_of_transport`` (the work of the joint servos; actuators on tendons,
such as the dm_control quadruped's lift and extend, count no work). ``straightness`` is the
forward displacement over the torso's path length sampled once per gait cycle (1: a straight
line). Perturbed worlds (``worlds = K``) as for the NAO, with the training pushes
scaled by the robot's mass over the NAO's (the same change of velocity).
"""

from __future__ import annotations

import math

import numpy as np

from evomotion.core.problem import Evaluation, GenomeSpec
from evomotion.errors import InputError
from evomotion.sim import nao
from evomotion.sim.backend import BatchedRollouts, make_simulator
from evomotion.sim.rollout import ServoWork, fall_step, fell, torso_track
from evomotion.studies.humanoid_walk import robot_gait
from evomotion.studies.humanoid_walk.problem import GRAVITY, HumanoidWalkConfig, soft_floor

METRICS = ("time_to_fall_s", "forward_m", "speed_mps", "lateral_m", "heading_change_rad",
           "heading_deg_per_m", "straightness", "cost_of_transport", "fell", "fall_rate")


class RobotWalkProblem(BatchedRollouts):
    """Batch evaluation of joint-space gaits of a robot spec (fitness maximised)."""

    sense = "max"
    metric_names = METRICS

    def __init__(self, cfg: HumanoidWalkConfig) -> None:
        from evomotion.sim.robot import load_robot

        self.cfg = cfg
        cfg.validate()
        r = self.robot = load_robot(cfg.robot)
        self.is_nao = False
        if r.gait_kind is None:
            raise InputError(f"problem.robot: {r.spec.path} has no [gait] section (the "
                             "channels of hip_pitch, knee, ankle_pitch, ...)")
        self.kind = r.gait_kind
        self.model = m = r.model
        self.dt = float(m.opt.timestep)
        names, lo, hi, self.default = robot_gait.gene_table(self.kind)
        self.genome = GenomeSpec(lo, hi, names=names)
        self.horizon_s = float(robot_gait.walk_seconds(np.array([hi[0]]), cfg.walk_s)[0]
                               + cfg.hold_s)
        self.nstep = int(math.ceil(self.horizon_s / self.dt))
        self.t = self.dt * np.arange(self.nstep)
        limited = m.actuator_ctrllimited.astype(bool)
        self.ctrl_lo = np.where(limited, m.actuator_ctrlrange[:, 0], -np.inf)
        self.ctrl_hi = np.where(limited, m.actuator_ctrlrange[:, 1], np.inf)
        self.sim = make_simulator(m, cfg, cfg.threads)
        self.segment_steps = max(1, int(round(cfg.segment_s / self.dt)))
        joint_servos = np.flatnonzero(m.actuator_trntype == 0)  # mjTRN_JOINT
        self.work = ServoWork(m, joint_servos) if joint_servos.size else None
        self.mass_kg = float(m.body_mass.sum())
        self.fall_height_m, self.fall_tilt_rad = r.fall_thresholds(cfg.fall_height_m,
                                                                   cfg.fall_tilt_rad)
        self.worlds = None
        if cfg.worlds > 1:
            from evomotion.sim.nao.worlds import Perturbation, World, draw_worlds

            push = cfg.train_push_ns * self.mass_kg / nao.TOTAL_MASS_KG
            self.worlds = [World(m)] + draw_worlds(
                m, Perturbation(push_ns=(-push, push)), cfg.worlds - 1,
                np.random.default_rng(max(cfg.world_seed, 0)), self.horizon_s,
                design=cfg.world_design)

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The kind's default gait and ``n - 1`` copies jittered by 5 % of each range."""
        n = max(int(n), 1)
        span = self.genome.upper - self.genome.lower
        x = self.default + 0.05 * span * rng.standard_normal((n, span.size))
        x[0] = self.default
        return np.clip(x, self.genome.lower, self.genome.upper)

    def controls(self, genomes: np.ndarray, t: np.ndarray | None = None) -> np.ndarray:
        """Actuator targets ``[P, T, nu]`` (every physics step unless ``t`` is given)."""
        r = self.robot
        return robot_gait.targets(genomes, self.kind, r.gait, r.pose, self.ctrl_lo,
                                  self.ctrl_hi, self.t if t is None else t, self.cfg.walk_s)

    def _fallen(self, states: np.ndarray) -> np.ndarray:
        return fell(states, self.fall_height_m, self.fall_tilt_rad)


    def simulate(self, genomes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """(states, controls) of a batch in the nominal world."""
        ctrl = self.controls(genomes)
        states, _ = self.sim.run_until(self.robot.state0, ctrl, self._fallen,
                                       self.segment_steps)
        return states, ctrl

    def _evaluate_batch(self, genomes: np.ndarray) -> Evaluation:
        period = genomes[:, 0]
        if self.worlds is None:
            return self.score(*self.simulate(genomes), period)
        from evomotion.sim.nao.worlds import aggregate_worlds, delayed_controls, simulate_worlds

        n, k = len(genomes), len(self.worlds)
        c = np.repeat(self.controls(genomes), k, axis=0)
        states = simulate_worlds(self.worlds * n, self.robot.state0, c, self.sim.nthread,
                                 stopped=self._fallen, segment_steps=self.segment_steps,
                                 simulator=self.sim)
        lat = np.tile([w.latency_steps for w in self.worlds], n)
        ev = self.score(states, delayed_controls(c, lat), np.repeat(period, k))
        return aggregate_worlds(ev, n, k, self.cfg.world_aggregate, self.cfg.world_quantile)

    def score(self, states: np.ndarray, ctrl: np.ndarray, period_s: np.ndarray) -> Evaluation:
        """Fitness and metrics of rollouts ``states[P, nstep, ns]`` under ``ctrl`` of gaits
        with periods ``period_s[P]``."""
        c = self.cfg
        walk_s = robot_gait.walk_seconds(np.asarray(period_s, float), c.walk_s)
        track = torso_track(states)
        fall = fall_step(track, self.fall_height_m, self.fall_tilt_rad)
        fell_ = fall < self.nstep
        last = np.minimum(fall, self.nstep - 1)
        rows = np.arange(len(states))
        yaw0 = track.yaw_rad[:, 0]
        d = track.xyz[rows, last, :2] - track.xyz[:, 0, :2]
        forward = np.cos(yaw0) * d[:, 0] + np.sin(yaw0) * d[:, 1]
        lateral = -np.sin(yaw0) * d[:, 0] + np.cos(yaw0) * d[:, 1]
        heading = track.yaw_rad[rows, last] - yaw0
        stride = np.maximum(np.round(np.asarray(period_s) / self.dt).astype(np.int64), 1)
        straight = straightness(track.xyz[:, :, :2], last, stride, forward)
        t_up = np.where(fell_, (fall + 1) * self.dt, self.nstep * self.dt)
        work = self.work(states, ctrl, last) if self.work is not None else np.zeros(len(rows))
        cot = work / (self.mass_kg * GRAVITY * np.maximum(forward, 0.1))
        h = np.abs(heading)
        quality = forward - c.heading_weight * h - c.lateral_weight * np.abs(lateral) \
            - c.excess_weight * np.maximum(h - c.heading_tolerance_rad_per_m
                                           * np.maximum(forward, 0.0), 0.0) \
            - c.energy_weight * cot
        fitness = np.where(fell_, np.minimum(t_up + 0.1 * np.clip(forward, -0.5, 0.5),
                                             self.horizon_s - 1e-3),
                           self.horizon_s + 1.0 + soft_floor(quality))
        metrics = {"time_to_fall_s": t_up, "forward_m": forward,
                   "speed_mps": forward / walk_s, "lateral_m": lateral,
                   "heading_change_rad": heading,
                   "heading_deg_per_m": np.degrees(h) / np.maximum(forward, 0.01),
                   "straightness": straight, "cost_of_transport": cot,
                   "fell": fell_.astype(float), "fall_rate": fell_.astype(float)}
        return Evaluation(fitness, metrics)


def straightness(xy: np.ndarray, last: np.ndarray, stride: np.ndarray,
                 forward: np.ndarray) -> np.ndarray:
    """Forward displacement over the length of the torso's path sampled once per gait cycle
    (``stride[P]`` steps, so the sway within a cycle does not count), up to step ``last[P]``:
    1 for a straight walk, less for a curved or zig-zag one, 0 for no progress."""
    out = np.zeros(len(xy))
    for s in np.unique(stride):
        rows = np.flatnonzero(stride == s)
        pts = xy[rows][:, ::s]  # [r, K, 2]
        k = np.arange(pts.shape[1])[None]
        seg = np.linalg.norm(np.diff(pts, axis=1), axis=2)  # [r, K-1]
        seg = seg * (k[:, 1:] * s <= last[rows, None])
        length = seg.sum(axis=1)
        out[rows] = np.where(length > 1e-6, np.maximum(forward[rows], 0.0)
                             / np.maximum(length, 1e-6), 0.0)  # no path: no progress
    return np.clip(out, 0.0, 1.0)
