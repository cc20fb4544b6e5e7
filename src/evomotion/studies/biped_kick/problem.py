"""The kick problem: batched MuJoCo rollouts of kick motions and their fitness (maximised).

Fitness (m) = ball travel along the goal direction (+x) - ``w_lateral`` |lateral travel|
- ``fall_penalty_m`` if the robot fell - ``zmp_penalty_m`` * (fraction of the kick's steps whose
CoP margin is below ``zmp_margin_m``). Ball travel is the displacement at the end of the
rollout (``roll_after_s`` after the motion ends) plus the remaining rolling distance
``v |v| / (2 a)`` with ``a`` the rolling deceleration measured in the scene
(:func:`scene.measured_deceleration`), so the rollout need not wait for the ball to stop.

Stability (seed step 5): per physics step the CoP of the two soles' net contact forces (MuJoCo
``contact`` sensors) and its margin inside the support polygon (the sole rectangles in contact),
computed with the support function over 32 directions (exact for edges normal to one of them,
otherwise within 0.5 % of the polygon size). A CoP within ``zmp_margin_m`` of the edge means the
stance foot starts to tip. Steps without any sole contact count as violations.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_fields, check_number
from evomotion.core.problem import Evaluation, GenomeSpec
from evomotion.sim import nao
from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track
from evomotion.studies.biped_kick import scene
from evomotion.studies.biped_kick.motion import GENES, SETTLE_S, execution_time_s, joint_targets

METRICS = ("distance_m", "lateral_m", "fell", "zmp_violation", "min_margin_m",
           "exec_time_s")
DIRECTIONS = np.stack([np.cos(np.arange(32) * np.pi / 16), np.sin(np.arange(32) * np.pi / 16)],
                      axis=1)


#: ``problem.nthread`` at most (one MjData per thread); ``rolling_m`` at most (m, a rolling
#: friction length); the ball's offset from its default place at most (m)
MAX_THREADS = 1024
MAX_ROLLING_M = 0.1
MAX_BALL_OFFSET_M = 1.0
#: the kick scene's physics step, for estimates before it is loaded
KICK_TIMESTEP_S = 0.004
#: doubles per individual and physics step: state (71), sensors (26), controls (22), the
#: support-polygon analysis, rounded up
ROLLOUT_DOUBLES_PER_STEP = 200


@dataclass(frozen=True)
class KickConfig:
    """The ``[problem]`` section of the biped-kick study."""

    rolling_m: float = 0.005
    ball_dx_m: float = 0.0  # ball offset from its default place in front of the right toe
    ball_dy_m: float = 0.0
    w_lateral: float = 0.5
    fall_penalty_m: float = 3.0
    zmp_penalty_m: float = 2.0
    zmp_margin_m: float = 0.005
    roll_after_s: float = 0.8
    fall_height_m: float = nao.FALL_HEIGHT_M
    fall_tilt_rad: float = nao.FALL_TILT_RAD
    nthread: int = 0  # mujoco.rollout threads; 0 = all cores

    def for_worker(self) -> KickConfig:
        """The config of a one-core evaluator worker: ``nthread`` 0 (all cores) becomes 1;
        an explicit thread count is kept."""
        return dataclasses.replace(self, nthread=1) if self.nthread == 0 else self

    def validate(self) -> None:
        """One-line :class:`InputError` for impossible settings (every float finite)."""
        check_fields(self, "problem")
        check_number("problem.rolling_m", self.rolling_m, lo=0.0, hi=MAX_ROLLING_M, lo_open=True)
        for key in ("ball_dx_m", "ball_dy_m"):
            check_number(f"problem.{key}", getattr(self, key), lo=-MAX_BALL_OFFSET_M,
                         hi=MAX_BALL_OFFSET_M)
        for key in ("w_lateral", "fall_penalty_m", "zmp_penalty_m", "roll_after_s"):
            check_number(f"problem.{key}", getattr(self, key), lo=0.0)
        check_number("problem.fall_height_m", self.fall_height_m, lo=0.0, lo_open=True)
        check_number("problem.fall_tilt_rad", self.fall_tilt_rad, lo=0.0, hi=math.pi,
                     lo_open=True)
        check_number("problem.nthread", self.nthread, lo=0, hi=MAX_THREADS, integer=True)

    def genome_dim(self) -> int:
        """The genome's length (for the memory check before the problem is built)."""
        return len(GENES)

    memory_keys = ("roll_after_s",)  # what memory_bytes depends on (for its message)

    def memory_bytes(self, pop_size: int) -> int:
        """Bytes of one batch's rollout at the longest kick: recorded states, sensors,
        controls and support-polygon temporaries (doubles) per physics step, twice."""
        longest = SETTLE_S + execution_time_s(np.array([[g[2] for g in GENES]]))[0]
        steps = math.ceil((longest + self.roll_after_s) / KICK_TIMESTEP_S)
        return 2 * 8 * pop_size * steps * ROLLOUT_DOUBLES_PER_STEP


def support_margin_batch(sensors: np.ndarray, sl: dict[str, slice]) -> np.ndarray:
    """CoP margin (m) inside the support polygon per step, ``[..., T]`` (-inf: no support)."""
    corners, weights, points = [], [], []
    for side in ("l", "r"):
        c = sensors[..., sl[f"{side}_contact"]]
        found = c[..., 0] > 0
        fz = np.where(found, np.abs(c[..., 3]), 0.0)
        centre = sensors[..., sl[f"{side}_sole"]][..., :2]
        ax = sensors[..., sl[f"{side}_xaxis"]][..., :2]
        ax = ax / np.maximum(np.linalg.norm(ax, axis=-1, keepdims=True), 1e-9)
        ay = np.stack([-ax[..., 1], ax[..., 0]], axis=-1)
        hx, hy = scene.SOLE_HALF_M
        for sx, sy in ((1, 1), (1, -1), (-1, 1), (-1, -1)):
            corner = centre + sx * hx * ax + sy * hy * ay
            corners.append(np.where(found[..., None], corner, np.nan))
        weights.append(fz)
        points.append(c[..., 4:6])
    w = np.stack(weights, axis=-1)
    total = w.sum(axis=-1)
    cop = (w[..., None] * np.stack(points, axis=-2)).sum(-2) / np.maximum(total, 1e-12)[..., None]
    C = np.stack(corners, axis=-2)  # [..., 8, 2]
    h = np.nanmax(np.where(np.isnan(C[..., 0])[..., None], -np.inf, C @ DIRECTIONS.T), axis=-2)
    margin = np.min(h - cop @ DIRECTIONS.T, axis=-1)
    return np.where(total > 0, margin, -np.inf)


class KickProblem:
    """Maximise the ball's travel to the goal with a stable, non-falling kick."""

    sense = "max"
    metric_names = METRICS

    def __init__(self, cfg: KickConfig = KickConfig()) -> None:
        self.cfg = cfg
        self.genome = GenomeSpec(np.array([g[1] for g in GENES]), np.array([g[2] for g in GENES]),
                                 names=tuple(g[0] for g in GENES))
        self.model = scene.load_scene(cfg.rolling_m)
        self.dt = float(self.model.opt.timestep)
        self.sl = scene.sensor_slices(self.model)
        self.decel = scene.measured_deceleration(cfg.rolling_m)
        self.sim = BatchSimulator(self.model, cfg.nthread)

    def ball_xy(self) -> np.ndarray:
        return scene.default_ball_xy(self.model) + np.array([self.cfg.ball_dx_m,
                                                             self.cfg.ball_dy_m])

    def evaluate(self, genomes: np.ndarray, ball_xy: np.ndarray | None = None) -> Evaluation:
        g = np.atleast_2d(np.asarray(genomes, dtype=float))
        exec_t = execution_time_s(g)
        # each individual is measured at its own end step, so that its result does not
        # depend on the other members of the batch (which only set how long the batch runs)
        end = np.ceil((SETTLE_S + exec_t + self.cfg.roll_after_s) / self.dt).astype(int)
        nstep = int(end.max())
        times = self.dt * np.arange(1, nstep + 1)
        ctrl = joint_targets(g, times)
        ball0 = self.ball_xy() if ball_xy is None else np.asarray(ball_xy, dtype=float)
        state0 = scene.initial_scene_state(self.model, ball0)
        states, sensors = self.sim.run_with_sensors(state0, ctrl)
        last = states[np.arange(len(g)), end - 1]
        qb = nao.state_qpos(self.model, last, scene.BALL_JOINT, 2)
        vb = nao.state_qvel(self.model, last, scene.BALL_JOINT, 2)
        final = qb + vb * np.linalg.norm(vb, axis=1, keepdims=True) / (2 * self.decel)
        travel = final - ball0
        fell = fall_step(torso_track(states), self.cfg.fall_height_m,
                         self.cfg.fall_tilt_rad) < end
        margin = support_margin_batch(sensors, self.sl)
        in_kick = (times[None, :] >= SETTLE_S) & (times[None, :] <= SETTLE_S + exec_t[:, None])
        bad = (margin < self.cfg.zmp_margin_m) & in_kick
        viol = bad.sum(1) / np.maximum(in_kick.sum(1), 1)
        min_margin = np.min(np.where(in_kick, margin, np.inf), axis=1)
        fitness = (travel[:, 0] - self.cfg.w_lateral * np.abs(travel[:, 1])
                   - self.cfg.fall_penalty_m * fell - self.cfg.zmp_penalty_m * viol)
        return Evaluation(fitness, {"distance_m": travel[:, 0], "lateral_m": travel[:, 1],
                                    "fell": fell.astype(float), "zmp_violation": viol,
                                    "min_margin_m": min_margin, "exec_time_s": exec_t})


def make_problem(cfg: KickConfig) -> KickProblem:
    return KickProblem(cfg)
