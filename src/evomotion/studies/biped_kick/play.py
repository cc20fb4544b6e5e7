"""``evomotion biped-kick play``: plan the kick point, approach, kick, and follow the ball until
it rests (paper 002's whole chain for one ball and target, field frame, metres, radians).

1. **Plan** (:func:`planning.plan_aimed_kick`): the aim ``a`` in [-30, +30] deg and the stand
   pose that puts the ball where the evolved kick wants it for that aim, moved sideways to the
   centre of the kick's tolerance to placement errors (:func:`.experiment.tolerant_offset`,
   measured on the straight kick: ``ball_tolerant_offset_m`` in the report); the cubic Bézier
   approach from the robot's pose to it.
2. **Walk**, in one MuJoCo simulation (NAO + ball, field frame) with the kick: given a
   ``humanoid-walk`` run (``--walk RUN``; the command's default is the shipped controller
   :data:`DEFAULT_WALK`), its closed-loop walk controller takes the robot there along the
   approach (:mod:`.controller_walk`); given a ``humanoid-repertoire`` run, the
   robot walks there with its steps, closed loop (:mod:`.walk_play`); otherwise with the
   walking model of :mod:`planning` (0.20 m/s, 0.6 rad/s on curves), which gives the approach
   time while the robot is placed at the stand pose (the approach is not simulated). The
   output's ``walk`` key says which.
3. **Kick** from where the robot really stands: the aim is recomputed from its heading (within
   +-30 deg; +-5 deg after a controller's walk, whose plan turns the robot to face the target
   within that: :data:`CONTROLLER_MAX_AIM_DEG`), the kick's motion for that aim is played
   (:func:`motion.joint_targets`), then the ball rolls on; the roll left after the rollout is
   ``v |v| / (2 a_roll)`` and lasts ``|v| / a_roll``. By default (``follow``) the kick **sees
   the ball**: the plan puts the ball where the kick wants it (no tolerance centre), and the
   kick's swing follows the ball's offset from there as far as the joint ranges and motor
   speeds allow, slowed where the motors need it, its foot rolled in the air where its ankle needs
   it (:mod:`.adaptive`, :func:`seen_kick`); with an
   aim table (``table``, ``--table``: :mod:`.aim_table`) its commanded aim is chosen from the
   ball's place too. ``follow=False`` (``--blind``): the kick as evolved, the ball planned at
   the tolerance centre (the behaviour before 2026-12-05's third session).

Reported: where the ball rests, its distance to the target and to the ball->target line
(``target_error_m``), the times, and whether the robot fell.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import FileFormatError, InputError
from evomotion.studies.biped_kick.motion import GENES, MAX_AIM_DEG
from evomotion.studies.biped_kick.planning import WalkModel, bezier_time, plan_aimed_kick, wrap
from evomotion.textio import decode_utf8, loads_json, read_file_bytes

#: the kick shipped with evomotion (evolved by ``evomotion run biped-kick``, see its docs)
DEFAULT_KICK = Path(__file__).with_name("default_kick.json")
#: the walk controller ``play`` walks with by default: a humanoid-walk run's exported
#: ``policy.npz`` and ``policy.json`` (where from: its ``source.json``)
DEFAULT_WALK = Path(__file__).with_name("default_walk")
WALK_MODEL = WalkModel()
MAX_KICK_BYTES = 1 << 20
#: with a walk controller (it turns on the spot cheaply) the plan aims at most this far from the
#: robot's heading (deg): a kick aimed further sits the ball beside the toe, where a 2 cm
#: placement error turns it by many degrees
CONTROLLER_MAX_AIM_DEG = 5.0


def read_kick(path: Path | None) -> tuple[np.ndarray, str]:
    """The genome of a kick: a biped-kick run folder (its ``best.json``; the folder's
    ``config.toml`` must name the study), a ``best.json``, or the shipped default. One-line
    errors name the file and what was expected."""
    if path is None:
        path = DEFAULT_KICK
    path = Path(path)
    if path.is_dir():
        check_kick_run(path)
    f = path / "best.json" if path.is_dir() else path
    if not f.exists():
        raise InputError(f"{f}: no such file (expected a biped-kick run folder or its "
                         "best.json)")
    rec = loads_json(decode_utf8(read_file_bytes(f, "kick (best.json)", MAX_KICK_BYTES), f), f)
    if not isinstance(rec, dict) or rec.get("study", "biped-kick") != "biped-kick":
        raise FileFormatError(f, None, "the best.json of a biped-kick run")
    g = rec.get("genome")
    if (not isinstance(g, list) or len(g) != len(GENES)
            or not all(isinstance(v, int | float) and not isinstance(v, bool)
                       and np.isfinite(v) for v in g)):
        raise FileFormatError(f, None, f"key 'genome': a list of {len(GENES)} finite numbers "
                                       "(the kick's genes)")
    for v, (name, lo, hi) in zip(g, GENES, strict=True):
        if not lo <= v <= hi:
            raise FileFormatError(f, None, f"gene {name} in [{lo}, {hi}], got {v}")
    return np.asarray(g, dtype=float), str(f)


def check_kick_run(run: Path, option: str = "--kick") -> None:
    """One-line error unless the folder ``run`` is a biped-kick run (its ``config.toml``)."""
    from evomotion.run.config import config_from_run_dir

    name, _ = config_from_run_dir(run)
    if name != "biped-kick":
        raise InputError(f"{option} {run}: a {name} run, expected a biped-kick run folder "
                         "(or its best.json)")


def walk_kind(path: Path, option: str = "--walk") -> str:
    """``"controller"`` for a humanoid-walk run folder, else ``"repertoire"`` (a
    humanoid-repertoire run or its ``repertoire/``, checked when it is read); a run of any
    other study is one :class:`InputError` line."""
    from evomotion.run.config import study_of_run

    p = Path(path)
    name = study_of_run(p)
    if name is not None:
        if name == "humanoid-walk":
            return "controller"
        if name != "humanoid-repertoire":
            raise InputError(f"{option} {path}: a {name} run, expected a humanoid-walk "
                             "run (its walk controller) or a humanoid-repertoire run")
    elif p.is_dir() and (p / "policy.json").is_file() and (p / "policy.npz").is_file():
        return "controller"  # exported controller files alone (the shipped default_walk/)
    return "repertoire"


def field_state(problem: Any, pose: np.ndarray, ball: np.ndarray) -> np.ndarray:
    """Kick-scene state with the robot's torso at the field pose (x, y, heading) in its crouch
    and the ball resting at ``ball``."""
    import mujoco

    from evomotion.sim.robots import nao
    from evomotion.studies.biped_kick import scene

    m = problem.model
    data = nao.initial_data(m)
    i = nao.qpos_address(m)
    data.qpos[i:i + 2] = pose[:2]
    data.qpos[i + 3:i + 7] = [np.cos(pose[2] / 2), 0.0, 0.0, np.sin(pose[2] / 2)]
    b = scene.ball_qpos_index(m)
    data.qpos[b:b + 7] = [ball[0], ball[1], scene.BALL_RADIUS_M + 1e-4, 1, 0, 0, 0]
    mujoco.mj_forward(m, data)
    return nao.get_state(m, data)


def play(problem: Any, genome: np.ndarray, robot: np.ndarray, ball: np.ndarray,
         target: np.ndarray, video: Path | None = None,
         repertoire: Path | None = None, follow: bool = True,
         table: Any = None, table_name: str = "kick aim table") -> dict[str, Any]:
    """Plan, walk, kick and roll; the report (and ``video`` of the whole simulation).
    ``follow``: the kick sees the ball (module doc, step 3); ``table``: and its commanded aim
    comes from that :class:`.aim_table.AimTable` (with ``follow``; one line naming
    ``table_name`` unless it was measured with ``problem``'s following)."""
    from evomotion.sim.robots import nao
    from evomotion.studies.biped_kick import scene
    from evomotion.studies.biped_kick.walk_play import SceneRun, walk

    if table is not None:
        if not follow:
            raise InputError("play: an aim table is for the kick that sees the ball "
                             "(follow=True)")
        from evomotion.studies.biped_kick.aim_table import check_following

        check_following(table, problem.cfg, table_name)
    g = np.asarray(genome, dtype=float)
    robot, ball, target = (np.asarray(v, dtype=float) for v in (robot, ball, target))
    root0 = nao.state_qpos(problem.model, nao.initial_state(problem.model), nao.ROOT_JOINT, 2)

    from evomotion.studies.biped_kick.experiment import tolerant_offset

    # the ball where a placement error costs least; a kick that sees the ball wants it in place
    tolerant = 0.0 if follow else tolerant_offset(problem, g)

    def ball_local(aims: np.ndarray) -> np.ndarray:
        rows = np.repeat(g[None], len(np.atleast_1d(aims)), axis=0)
        return problem.ball_xy(rows, np.atleast_1d(aims)) - root0 + np.array([0.0, tolerant])

    controller = repertoire is not None and walk_kind(repertoire) == "controller"
    max_aim = np.radians(CONTROLLER_MAX_AIM_DEG if controller else MAX_AIM_DEG)
    plan = plan_aimed_kick(robot, ball, target, ball_local, max_aim)
    path_m, model_s = bezier_time(plan.control_points, WALK_MODEL)
    report: dict[str, Any] = {"walk_path_m": path_m, "ball_tolerant_offset_m": tolerant}
    if repertoire is None:
        run = SceneRun(problem, field_state(problem, plan.pose, ball))
        report.update(walk=f"walking model ({WALK_MODEL.speed_m_s} m/s, "
                           f"{WALK_MODEL.turn_rad_s} rad/s); the approach is not simulated",
                      walk_time_s=model_s)
    elif controller:
        from evomotion.studies.biped_kick.controller_walk import walk_controller

        run = SceneRun(problem, field_state(problem, robot, ball))
        w = walk_controller(run, Path(repertoire), plan.pose, plan.control_points)
        report.update(walk=f"controller {repertoire} (closed loop, simulated)",
                      walk_time_s=run.time_s, walk_reached=w["reached"],
                      walk_position_error_m=w["position_error_m"],
                      walk_heading_error_deg=w["heading_error_deg"])
    else:
        run = SceneRun(problem, field_state(problem, robot, ball))
        w = walk(run, repertoire, plan.control_points, plan.pose)
        report.update(walk=f"repertoire {repertoire} (closed-loop steps, simulated)",
                      walk_time_s=run.time_s, walk_steps=w["steps"],
                      walk_position_error_m=w["position_error_m"],
                      walk_heading_error_deg=w["heading_error_deg"])
    walk_s = run.time_s if repertoire is not None else model_s
    report["time_to_kick_s"] = None
    if run.fell:  # fell while walking: there is nothing to kick with
        rest = nao.state_qpos(problem.model, run.state, scene.BALL_JOINT, 2)
        report.update(ball_rest_m=[float(rest[0]), float(rest[1])],
                      target_error_m=None, time_s=float(walk_s), fell=True,
                      kicked=False, target_distance_m=float(np.linalg.norm(rest - target)))
        return _with_video(report, run, problem, video)
    pose = run.pose()
    ball_now = nao.state_qpos(problem.model, run.state, scene.BALL_JOINT, 2)
    psi_t = float(np.arctan2(*(target - ball_now)[::-1]))  # the walk may have nudged the ball
    aim = float(np.clip(wrap(psi_t - pose[2]), -max_aim, max_aim))
    c, s = np.cos(pose[2]), np.sin(pose[2])
    d = ball_now - pose[:2]
    local = np.array([c * d[0] + s * d[1], -s * d[0] + c * d[1]])
    placement = float(np.linalg.norm(local - ball_local(np.array([aim]))[0]))
    seen: dict[str, Any] = {}
    if follow:
        command, g_kick, shift, seen = seen_kick(problem, g, aim, local + root0, table)
        _, ctrl, end, _ = problem.controls(g_kick[None], np.array([command]), shift[None])
    else:
        _, ctrl, end, _ = problem.controls(g[None], np.array([aim]))
    nstep = int(end[0])
    states = run.play(ctrl[0])
    rest, roll = problem.ball_rest(states[-1])
    roll_s = float(roll)
    u = (target - ball) / max(np.linalg.norm(target - ball), 1e-12)
    r = rest - ball
    report.update({
        "ball_rest_m": [float(rest[0]), float(rest[1])],
        "target_error_m": float(abs(u[0] * r[1] - u[1] * r[0])),
        "target_distance_m": float(np.linalg.norm(rest - target)),
        "time_s": float(walk_s + nstep * problem.dt + roll_s),
        "fell": bool(run.fell),
        "aim_deg": float(np.degrees(aim)),
        "planned_stand_pose": [float(plan.pose[0]), float(plan.pose[1]),
                               wrap(float(plan.pose[2]))],
        "stand_pose": [float(x) for x in pose],
        "ball_placement_error_m": placement,
        "kick_time_s": float(nstep * problem.dt), "roll_time_s": roll_s,
        "time_to_kick_s": float(walk_s + contact_s(states, problem)),
        "kick_distance_m": float(np.linalg.norm(r)),
        **seen,
    })
    report["kicked"] = True
    return _with_video(report, run, problem, video)


def seen_kick(problem: Any, g: np.ndarray, aim: float, ball_xy: np.ndarray, table: Any = None
              ) -> tuple[float, np.ndarray, np.ndarray, dict[str, Any]]:
    """The kick of genome ``g`` at ``aim`` (rad) that sees its ball at ``ball_xy`` (the kick
    problem's frame: the robot's root at rest at its origin, facing +x): its commanded aim (from
    ``table`` if given), its genome with the swing slowed where its motors need it, the swing's
    shift towards the ball (:mod:`.adaptive`) and what to report."""
    from evomotion.studies.biped_kick.adaptive import following

    if table is not None:
        from evomotion.studies.biped_kick.aim_table import command

        aim = float(np.radians(command(table, problem, g, float(np.degrees(aim)),
                                       ball_xy[None])[0]))
    rows, aims = g[None], np.array([aim])
    g_kick, shift, frac, stretch = following(problem, rows, aims, ball_xy[None],
                                             np.zeros(1, bool))
    want = ball_xy - problem.wanted_ball_xy(rows, aims)[0]
    return aim, g_kick[0], shift[0], {
        "command_deg": float(np.degrees(aim)), "ball_offset_m": [float(v) for v in want],
        "followed_fraction": float(frac[0]), "swing_stretch": float(stretch[0])}


def _with_video(report: dict[str, Any], run: Any, problem: Any, video: Path | None
                ) -> dict[str, Any]:
    from evomotion.studies.biped_kick import scene

    if video is not None:
        from evomotion.sim.render import RenderUnavailableError, render_video

        try:
            render_video(np.concatenate(run.qpos), problem.dt, video, camera="kick",
                         model_xml=scene.kick_scene_xml(rolling_m=problem.cfg.rolling_m))
            report["video"] = str(video)
        except (RenderUnavailableError, RuntimeError) as exc:
            report["video"] = None
            report["video_skipped"] = str(exc)
    return report


def contact_s(states: np.ndarray, problem: Any) -> float:
    """Time (s) from the start of ``states`` (the kick's rollout) until the ball first moves
    faster than 5 cm/s (the foot meets it); the whole rollout if it never does."""
    from evomotion.sim.robots import nao
    from evomotion.studies.biped_kick import scene

    v = nao.state_qvel(problem.model, states, scene.BALL_JOINT, 2)
    moving = np.linalg.norm(v, axis=-1) > 0.05
    return float((int(np.argmax(moving)) + 1 if moving.any() else len(states)) * problem.dt)
