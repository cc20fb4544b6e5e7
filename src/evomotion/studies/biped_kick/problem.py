"""The kick problem: batched MuJoCo rollouts of aimed kicks, with the ZMP as a constraint.

Every genome kicks once per training aim ``a`` in ``problem.aims_deg`` (from the foot's heading,
+ to the left), the ball placed where the kick wants it (:func:`motion.ball_offset`, plus
``ball_dx_m``/``ball_dy_m``). Ball travel is the displacement at the end of the rollout
(``roll_after_s`` after the motion) plus the remaining roll ``v |v| / (2 a_roll)`` with
``a_roll`` the rolling deceleration measured in the scene (:func:`scene.measured_deceleration`).

Objective (m, maximised) = mean over aims of [travel along ``a`` - ``w_angle_m_per_rad`` |angle
error|] - ``w_time_m_per_s`` x execution time.

Constraints (the paper's step 5: an unstable kick is rejected and the search goes on): during the
kick, the centre of pressure of the soles' contact forces (MuJoCo ``contact`` sensors) stays at
least ``zmp_margin_m`` inside the support polygon (the sole rectangles in contact; margin by the
support function over 32 directions), at every physics step; the robot does not fall; every
20 ms key pose of every aim is within the NAO's joint ranges and moves no faster than
``speed_margin`` x its motor's no-load speed. Violation (>= 0, unitless) = mean over aims of
[fell + ZMP deficit / 1 mm s] + the largest range excess over the aims / 0.01 rad + the
largest speed excess / 0.01 s, where the ZMP deficit is ``sum_t min(max(0, zmp_margin_m -
margin_t), zmp_margin_m + 5 cm) dt`` (a step without sole contact counts as
``zmp_margin_m + 5 cm`` short). Selection is feasibility-first
(:mod:`evomotion.core.constraints`, Deb 2000): fitness is the objective for feasible kicks and
``FLOOR_M - 1 - violation`` otherwise.

The robot is ``problem.robot`` (default the NAO, as above); another biped kicks through the
numerical leg IK in its own scene (:mod:`.kickers`, :mod:`.robot_motion`,
:mod:`.robot_scene`): its sole rectangle, its actuators' ranges, motor speeds only where its
spec has them, its ``[fall]`` thresholds unless ``fall_height_m``/``fall_tilt_rad`` are set.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass

import numpy as np

from evomotion.core.checks import check_fields, check_number, check_text
from evomotion.core.constraints import feasibility_first
from evomotion.core.problem import Evaluation, GenomeSpec, Sense
from evomotion.errors import InputError
from evomotion.sim.robots import nao
from evomotion.sim.rollout import BatchSimulator, fall_step, interpolate_controls, torso_track
from evomotion.sim.worlds import World, simulate_worlds
from evomotion.studies.biped_kick import scene
from evomotion.studies.biped_kick.adaptive import (
    MAX_FOOT_ROLL_RAD,
    MAX_STRETCH,
    following,
    following_keys,
    left_flags,
)
from evomotion.studies.biped_kick.balance import MAX_GAIN_S, BalanceFeedback, control_steps
from evomotion.studies.biped_kick.kickers import kicker_for
from evomotion.studies.biped_kick.motion import (
    GENES,
    MAX_AIM_DEG,
    SETTLE_S,
    ball_offset,
    execution_time_s,
    key_times,
    limit_excess,
)
from evomotion.studies.biped_kick.planning import wrap

METRICS = ("distance_m", "angle_error_deg", "lateral_m", "fell", "feasible", "violation",
           "zmp_deficit_mm_s", "min_margin_m", "speed_ratio", "exec_time_s")
DIRECTIONS = np.stack([np.cos(np.arange(32) * np.pi / 16), np.sin(np.arange(32) * np.pi / 16)],
                      axis=1)
#: no feasible kick scores below this (m): the ball does not roll 20 m backwards
FLOOR_M = -20.0
NO_SUPPORT_DEFICIT_M = 0.05
ZMP_UNIT_M_S = 1e-3
LIMIT_UNIT_RAD = 0.01
SPEED_UNIT_S = 0.01
#: ``problem.nthread`` at most; ``rolling_m`` at most (m); ball offset at most (m)
MAX_THREADS = 1024
MAX_ROLLING_M = 0.1
MAX_BALL_OFFSET_M = 1.0
MAX_AIMS = 16
#: the documented ranges of the other ``[problem]`` floats: weights (m per rad, m per s),
#: the roll after the kick (s), the ZMP margin (m; a NAO sole is 0.16 x 0.09 m), fall
#: height (m)
MAX_WEIGHT = 1000.0
MAX_ROLL_AFTER_S = 60.0
MAX_ZMP_MARGIN_M = 0.1
MAX_FALL_HEIGHT_M = 5.0
KICK_TIMESTEP_S = 0.004  # the kick scene's physics step, for estimates before it is loaded
#: doubles per rollout and physics step: state (84), sensors (26), controls (22), support
#: polygon temporaries, rounded up
ROLLOUT_DOUBLES_PER_STEP = 220


@dataclass(frozen=True)
class KickConfig:
    """The ``[problem]`` section of the biped-kick study."""

    rolling_m: float = scene.CARPET_ROLLING_M  # m; calibrated to 0.35 m/s^2 (scene.py)
    ball_dx_m: float = 0.0  # ball offset from where the kick wants it (m)
    ball_dy_m: float = 0.0
    aims_deg: tuple[float, ...] = (-30.0, -15.0, 0.0, 15.0, 30.0)
    w_angle_m_per_rad: float = 3.0
    w_time_m_per_s: float = 0.05
    zmp_margin_m: float = 0.005
    speed_margin: float = 1.0
    roll_after_s: float = 0.8
    fall_height_m: float = nao.FALL_HEIGHT_M
    fall_tilt_rad: float = nao.FALL_TILT_RAD
    nthread: int = 0  # mujoco.rollout threads; 0 = all cores
    #: the robot: "" or "nao" (the NAO, its closed-form leg IK), another bundled biped (op3)
    #: or a spec .toml (sim/robots): the same kick, scaled to its size, through the numerical
    #: leg IK (robot_motion.py); its [fall] thresholds apply unless fall_height_m /
    #: fall_tilt_rad are set
    robot: str = ""
    #: balance feedback during the kick (balance.py, eq. 1): the support ankle's pitch and
    #: roll targets move by these gains (s) x the torso's pitch and roll rates (rad/s), read
    #: every control_period_s (s); (0, 0): the open-loop kick (the NAO's kick only)
    balance_gains: tuple[float, float] = (0.0, 0.0)
    control_period_s: float = 0.012
    #: a kick that follows the ball (kicks(adapt=True), adaptive.py) may lengthen its swing
    #: up to this factor to stay within the motors' speeds (1: its evolved timing only)
    adapt_max_stretch: float = 1.25
    #: and its foot, in the air, may roll up to this far (rad) where its ankle's roll would
    #: leave the joint's range to keep the sole level (adaptive.rolled_in_air; 0: level)
    adapt_foot_roll_rad: float = 0.1

    def for_worker(self) -> KickConfig:
        """The config of a one-core evaluator worker: ``nthread`` 0 (all cores) becomes 1."""
        return dataclasses.replace(self, nthread=1) if self.nthread == 0 else self

    def validate(self) -> None:
        """One-line :class:`InputError` for impossible settings (every float finite)."""
        check_fields(self, "problem")
        check_number("problem.rolling_m", self.rolling_m, lo=0.0, hi=MAX_ROLLING_M, lo_open=True)
        for key in ("ball_dx_m", "ball_dy_m"):
            check_number(f"problem.{key}", getattr(self, key), lo=-MAX_BALL_OFFSET_M,
                         hi=MAX_BALL_OFFSET_M)
        if not 1 <= len(self.aims_deg) <= MAX_AIMS:
            raise InputError(f"problem.aims_deg: expected 1 to {MAX_AIMS} aims (degrees), got "
                             f"{len(self.aims_deg)}")
        lim = MAX_AIM_DEG
        for i, a in enumerate(self.aims_deg):
            check_number(f"problem.aims_deg[{i}]", a, lo=-lim, hi=lim)
        for key, hi in (("w_angle_m_per_rad", MAX_WEIGHT), ("w_time_m_per_s", MAX_WEIGHT),
                        ("roll_after_s", MAX_ROLL_AFTER_S), ("zmp_margin_m", MAX_ZMP_MARGIN_M)):
            check_number(f"problem.{key}", getattr(self, key), lo=0.0, hi=hi)
        check_number("problem.speed_margin", self.speed_margin, lo=0.0, hi=1.0, lo_open=True)
        check_number("problem.adapt_max_stretch", self.adapt_max_stretch, lo=1.0,
                     hi=MAX_STRETCH)
        check_number("problem.adapt_foot_roll_rad", self.adapt_foot_roll_rad, lo=0.0,
                     hi=MAX_FOOT_ROLL_RAD)

        check_number("problem.fall_height_m", self.fall_height_m, lo=0.0,
                     hi=MAX_FALL_HEIGHT_M, lo_open=True)
        check_number("problem.fall_tilt_rad", self.fall_tilt_rad, lo=0.0, hi=math.pi,
                     lo_open=True)
        check_number("problem.nthread", self.nthread, lo=0, hi=MAX_THREADS, integer=True)
        check_text("problem.robot", self.robot)
        if len(self.balance_gains) != 2:
            raise InputError("problem.balance_gains: expected two gains (s), the support "
                             f"ankle's pitch and roll, got {len(self.balance_gains)}")
        for i, g in enumerate(self.balance_gains):
            check_number(f"problem.balance_gains[{i}]", g, lo=-MAX_GAIN_S, hi=MAX_GAIN_S)
        check_number("problem.control_period_s", self.control_period_s, lo=0.0, hi=1.0,
                     lo_open=True)

    def genome_dim(self) -> int:
        return len(GENES)

    memory_keys = ("aims_deg", "roll_after_s")  # what memory_bytes depends on

    def memory_bytes(self, pop_size: int) -> int:
        """Bytes of one batch's rollouts at the longest kick, twice."""
        longest = SETTLE_S + execution_time_s(np.array([[g[2] for g in GENES]]))[0]
        steps = math.ceil((longest + self.roll_after_s) / KICK_TIMESTEP_S)
        return 2 * 8 * pop_size * len(self.aims_deg) * steps * ROLLOUT_DOUBLES_PER_STEP


def support_margin_batch(sensors: np.ndarray, sl: dict[str, slice],
                         sole_half: tuple[float, float] = scene.SOLE_HALF_M) -> np.ndarray:
    """CoP margin (m) inside the support polygon per step, ``[..., T]`` (-inf: no support)."""
    return support_analysis(sensors, sl, sole_half)[0]


def support_analysis(sensors: np.ndarray, sl: dict[str, slice],
                     sole_half: tuple[float, float] = scene.SOLE_HALF_M
                     ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(margin ``[..., T]`` (m, -inf: no support), CoP ``[..., T, 2]`` (world, m), sole
    corners ``[..., T, 8, 2]`` (NaN for a sole not in contact)); ``sole_half``: the sole
    rectangle's half length and width (m; default the NAO's)."""
    corners, weights, points = [], [], []
    for side in ("l", "r"):
        c = sensors[..., sl[f"{side}_contact"]]
        found = c[..., 0] > 0
        fz = np.where(found, np.abs(c[..., 3]), 0.0)
        centre = sensors[..., sl[f"{side}_sole"]][..., :2]
        ax = sensors[..., sl[f"{side}_xaxis"]][..., :2]
        ax = ax / np.maximum(np.linalg.norm(ax, axis=-1, keepdims=True), 1e-9)
        ay = np.stack([-ax[..., 1], ax[..., 0]], axis=-1)
        hx, hy = sole_half
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
    return np.where(total > 0, margin, -np.inf), np.where((total > 0)[..., None], cop, np.nan), C


class KickProblem:
    """Maximise the ball's travel along the requested aims with a stable, feasible kick, on
    ``cfg.robot`` (the NAO by default; a biped with feet ``left`` and ``right``): the robot's
    kicker (:func:`.kickers.kicker_for`) gives its genome bounds, scene and joint targets."""

    sense: Sense = "max"
    # the instance's: with ``ik_error_m`` for the numerical IK
    metric_names: tuple[str, ...] = METRICS

    def __init__(self, cfg: KickConfig = KickConfig()) -> None:
        from evomotion.sim.robots import load_robot

        self.cfg = cfg
        r = self.robot = load_robot(cfg.robot or "nao")
        if set(r.feet) != {"left", "right"}:
            raise InputError(f"problem.robot: {r.name} has feet {', '.join(r.feet)}; a kick "
                             "needs a biped with feet 'left' and 'right'")
        k = self.kicker = kicker_for(r, cfg)
        if k.name == "numerical":
            self.metric_names = (*METRICS, "ik_error_m")
        self.genome = GenomeSpec(k.lower, k.upper, names=tuple(g[0] for g in GENES))
        self.model = k.model
        self.dt = float(self.model.opt.timestep)
        self.sl = scene.sensor_slices(self.model)
        self.decel = k.decel
        self.sim = BatchSimulator(self.model, cfg.nthread)
        self.aims_rad = np.radians(np.asarray(cfg.aims_deg, dtype=float))
        self._toe = k.toe
        self.fall_height_m, self.fall_tilt_rad = r.fall_thresholds(cfg.fall_height_m,
                                                                   cfg.fall_tilt_rad)
        self.closed_loop = any(g != 0 for g in cfg.balance_gains)
        self.control_steps = 0
        if self.closed_loop:  # its checks: the period, the robot's ankles
            self.control_steps = control_steps(self.model, cfg.control_period_s)
            BalanceFeedback(self.model, cfg.balance_gains, np.zeros(0, bool))

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The hand-set kick :data:`.motion.START` (CMA-ES starts its mean there) and ``n - 1``
        copies jittered by 5 % of each gene's range (for the GA)."""
        n = max(int(n), 1)
        span = self.genome.upper - self.genome.lower
        start = self.kicker.start
        x = start + 0.05 * span * rng.standard_normal((n, span.size))
        x[0] = start
        return np.clip(x, self.genome.lower, self.genome.upper)

    def wanted_ball_xy(self, genomes: np.ndarray, aims_rad: np.ndarray) -> np.ndarray:
        """Where each (right-foot) kick wants the ball (world, m) ``[B, 2]``."""
        y = ball_offset(genomes, aims_rad)
        x = np.full_like(y, self._toe[0] + scene.BALL_RADIUS_M + self.kicker.gap_m)
        return np.stack([x, self._toe[1] + y], axis=1)

    def ball_xy(self, genomes: np.ndarray, aims_rad: np.ndarray) -> np.ndarray:
        """Where each kick wants the ball (world, m) plus the configured offset ``[B, 2]``."""
        return self.wanted_ball_xy(genomes, aims_rad) + [self.cfg.ball_dx_m,
                                                         self.cfg.ball_dy_m]

    def controls(self, genomes: np.ndarray, aims_rad: np.ndarray,
                 ball_shift: np.ndarray | None = None
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray | None]:
        """(20 ms key poses ``[n, K, nu]``, physics-step targets ``[n, nstep, nu]``, each
        kick's end step ``[n]``: the motion plus ``roll_after_s``, each kick's IK error ``[n]``
        (m; ``None`` for the closed-form IK)); with a ``ball_shift`` (a kick that follows the
        ball) the kicking foot may roll in the air (:func:`.adaptive.rolled_in_air`, by at
        most ``problem.adapt_foot_roll_rad``). Each kick is measured at its own end step, so
        its result does not depend on the other members of the batch (which only set how long
        the batch runs)."""
        end = np.ceil((SETTLE_S + execution_time_s(genomes) + self.cfg.roll_after_s)
                      / self.dt).astype(int)
        kt = key_times(genomes)
        keys, ik_error = following_keys(self.kicker, np.atleast_2d(genomes), kt, aims_rad,
                                        ball_shift, self.cfg.adapt_foot_roll_rad)
        return keys, interpolate_controls(kt, keys, self.dt, int(end.max())), end, ik_error

    def ball_rest(self, states: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Where the ball of recorded ``states[..., nstate]`` comes to rest (``[..., 2]``, m:
        its place plus the remaining roll ``v |v| / (2 a_roll)``) and how long it still rolls
        (``|v| / a_roll``, s)."""
        q = nao.state_qpos(self.model, states, scene.BALL_JOINT, 2)
        v = nao.state_qvel(self.model, states, scene.BALL_JOINT, 2)
        speed = np.linalg.norm(v, axis=-1)
        return q + v * speed[..., None] / (2 * self.decel), speed / self.decel

    def kicks(self, genomes: np.ndarray, aims_rad: np.ndarray, ball_xy: np.ndarray,
              keep: bool = False, worlds: list | None = None,
              adapt: bool = False, left_foot: np.ndarray | bool = False
              ) -> dict[str, np.ndarray]:
        """One rollout per row: genome ``[n, d]``, aim ``[n]`` (rad), ball ``[n, 2]`` (world).
        Per-kick results; with ``keep`` also ``states``, ``sensors``, ``margin``, ``end``.
        ``worlds``: one perturbed :class:`~evomotion.sim.worlds.World` of this problem's
        model per row (:func:`.experiment.kick_worlds`), else the nominal model. ``adapt``:
        the kicking foot's swing follows the ball's offset from where the kick wants it
        (:func:`.motion.foot_trajectories`' ``ball_shift``; the robot stands at the origin
        facing +x, so world and robot frames agree), as far as the joint ranges and motor
        speeds allow (:mod:`.adaptive`; ``adapt_fraction`` in the results). ``left_foot``
        (one flag, or one per kick): kick with the left foot, the right-foot kick in mirror
        image (the NAO's kicker only): its aim and ball mirrored for the motion, the rollout
        in the real scene."""
        g = np.atleast_2d(np.asarray(genomes, dtype=float))
        aims = np.broadcast_to(np.asarray(aims_rad, dtype=float), (len(g),))
        ball0 = np.asarray(ball_xy, dtype=float).reshape(len(g), 2)
        left = left_flags(left_foot, len(g), self.kicker.mirror, self.robot.name)
        flip = np.where(left, -1.0, 1.0)
        aims_k = aims * flip  # the right-foot kick's aim and ball, mirrored where left
        ball_k = ball0 * np.stack([np.ones(len(g)), flip], axis=1)
        shift, frac, stretch = None, np.zeros(len(g)), np.ones(len(g))
        if adapt:
            g, shift, frac, stretch = following(self, g, aims_k, ball_k, left)
        exec_t = execution_time_s(g)
        keys, ctrl, end, ik_error = self.controls(g, aims_k, shift)
        if left.any():
            mirror = self.kicker.mirror
            assert mirror is not None  # left_flags refuses a left kick without a mirror image
            keys[left], ctrl[left] = mirror(keys[left]), mirror(ctrl[left])
        nstep = ctrl.shape[1]
        state0 = np.stack([self.kicker.initial_state(b) for b in ball0])
        if worlds is not None and len(worlds) != len(g):
            raise InputError(f"kicks: expected one world per kick ({len(g)}), got "
                             f"{len(worlds)}")
        if worlds is None and not self.closed_loop:
            states, sensors = self.sim.run_with_sensors(state0, ctrl)
        else:  # perturbed worlds, or the balance feedback's closed loop (balance.py)
            fb = (BalanceFeedback(self.model, self.cfg.balance_gains, left)
                  if self.closed_loop else None)
            states, sensors = simulate_worlds(
                worlds if worlds is not None else [World(self.model)] * len(g), state0, ctrl,
                self.cfg.nthread, sensors=True, feedback=fb, control_steps=self.control_steps)
        rest, roll_s = self.ball_rest(states[np.arange(len(g)), end - 1])
        travel = rest - ball0
        along, lateral, angle_err = against_aim(travel, aims)
        fell = fall_step(torso_track(states), self.fall_height_m, self.fall_tilt_rad) < end
        margin = support_margin_batch(sensors, self.sl, self.kicker.sole_half)
        times = self.dt * np.arange(1, nstep + 1)
        in_kick = (times[None, :] >= SETTLE_S) & (times[None, :] <= SETTLE_S + exec_t[:, None])
        short = np.minimum(np.maximum(self.cfg.zmp_margin_m - margin, 0.0),
                           self.cfg.zmp_margin_m + NO_SUPPORT_DEFICIT_M)
        # a sequential sum: the steps after a kick's end add exact zeros (batch-independent)
        deficit = np.cumsum(np.where(in_kick, short, 0.0), axis=1)[:, -1] * self.dt
        range_x, speed_x, speed_ratio = limit_excess(keys, self.cfg.speed_margin,
                                                     self.kicker.limits)
        out = {"travel": travel, "along_m": along, "lateral_m": lateral, "adapt_fraction": frac,
               "stretch": stretch,
               "angle_error_rad": angle_err, "fell": fell, "zmp_deficit_m_s": deficit,
               "min_margin_m": np.min(np.where(in_kick, margin, np.inf), axis=1),
               "range_excess_rad": range_x, "speed_excess_s": speed_x,
               "speed_ratio": speed_ratio, "exec_time_s": exec_t, "ball0": ball0,
               "rest_xy": rest, "roll_s": roll_s}
        if ik_error is not None:
            out["ik_error_m"] = ik_error
        if keep:
            out.update(states=states, sensors=sensors, margin=margin, end=end, times=times)
        return out

    def evaluate(self, genomes: np.ndarray) -> Evaluation:
        g = np.atleast_2d(np.asarray(genomes, dtype=float))
        n, na = len(g), len(self.aims_rad)
        rows = np.repeat(g, na, axis=0)
        aims = np.tile(self.aims_rad, n)
        k = self.kicks(rows, aims, self.ball_xy(rows, aims))

        def per(name: str) -> np.ndarray:
            return np.asarray(k[name], dtype=float).reshape(n, na)

        cfg = self.cfg
        exec_t = execution_time_s(g)
        objective = (per("along_m") - cfg.w_angle_m_per_rad * np.abs(per("angle_error_rad"))
                     ).mean(1) - cfg.w_time_m_per_s * exec_t
        violation = ((per("fell") + per("zmp_deficit_m_s") / ZMP_UNIT_M_S).mean(1)
                     + per("range_excess_rad").max(1) / LIMIT_UNIT_RAD
                     + per("speed_excess_s").max(1) / SPEED_UNIT_S)
        fitness = feasibility_first(objective, violation, self.sense, FLOOR_M)
        return Evaluation(fitness, {
            "distance_m": per("along_m").mean(1),
            "angle_error_deg": np.degrees(np.abs(per("angle_error_rad"))).mean(1),
            "lateral_m": np.abs(per("lateral_m")).mean(1),
            "fell": per("fell").max(1), "feasible": (violation <= 0).astype(float),
            "violation": violation, "zmp_deficit_mm_s": per("zmp_deficit_m_s").mean(1) * 1e3,
            "min_margin_m": per("min_margin_m").min(1), "speed_ratio": per("speed_ratio").max(1),
            "exec_time_s": exec_t,
            **({"ik_error_m": per("ik_error_m").max(1)} if "ik_error_m" in k else {})})


def against_aim(travel: np.ndarray, aims_rad: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(along, lateral (m, + left), angle error (rad, wrapped)) of balls' ``travel[n, 2]``
    against the aims ``aims_rad[n]``."""
    u = np.stack([np.cos(aims_rad), np.sin(aims_rad)], axis=1)
    return ((travel * u).sum(1), u[:, 0] * travel[:, 1] - u[:, 1] * travel[:, 0],
            wrap(np.arctan2(travel[:, 1], travel[:, 0]) - aims_rad))


def make_problem(cfg: KickConfig) -> KickProblem:
    return KickProblem(cfg)
