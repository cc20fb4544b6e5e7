"""Keyframe-kick baseline (the approach paper 002 attributes to HTWK): Webots' ``Shoot.motion``
replayed open loop in the kick scene, measured like the optimised kick.

The motion ships with evomotion
(:func:`evomotion.sim.robots.nao.webots_motions.shipped_motion`; Webots,
Apache-2.0) and is played as Webots' motion player does (linear interpolation of the key poses,
:func:`evomotion.sim.robots.nao.replay.motion_targets`). The kicking foot is the one whose
ankle (leg FK
in the torso frame) reaches furthest forward during the motion; the ball is placed ``gap_m`` in
front of that foot's toe in the motion's first pose, plus the given offsets. Execution time is
the motion's duration; the minimum ZMP margin is taken over it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evomotion.sim.motion import Motion, read_motion
from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.leg_ik import leg_fk
from evomotion.sim.robots.nao.replay import motion_targets
from evomotion.sim.robots.nao.webots_motions import shipped_motion
from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track
from evomotion.studies.biped_kick import scene
from evomotion.studies.biped_kick.problem import KickConfig, support_margin_batch


def shoot_motion(path: str | Path | None = None) -> Motion:
    """The keyframe kick: the ``.motion`` at ``path``, else the shipped Webots ``Shoot``."""
    return shipped_motion("Shoot") if path is None else read_motion(path)


def kicking_foot(motion: Motion) -> str:
    """``"l"`` or ``"r"``: the foot whose ankle goes furthest forward (torso frame)."""
    reach: dict[str, float] = {}
    for side, names, left in (("l", nao.LEFT_LEG, True), ("r", nao.RIGHT_LEG, False)):
        q = np.stack([np.nan_to_num(motion.column(n)) for n in names], axis=1)
        reach[side] = float(leg_fk(q, left)[0][:, 0].max())
    return max(reach, key=reach.__getitem__)


def keyframe_kicks(offsets_m: np.ndarray, path: str | Path | None = None,
                   cfg: KickConfig = KickConfig(), hold_s: float = 0.8) -> dict[str, np.ndarray]:
    """Replay the motion once per ball offset ``[n, 2]``: distance, lateral, fell, time."""
    motion = shoot_motion(path)
    model = scene.load_scene(cfg.rolling_m)
    dt = float(model.opt.timestep)
    nstep = int(np.ceil((motion.duration_s + hold_s) / dt))
    first, ctrl = motion_targets(motion, dt, nstep)
    foot = kicking_foot(motion)
    ball0 = scene.default_ball_xy(model, pose=first, foot=foot)
    decel = scene.measured_deceleration(cfg.rolling_m)
    out: dict[str, list[float]] = {
        k: [] for k in ("distance_m", "lateral_m", "fell", "exec_time_s", "min_margin_m")}
    sl = scene.sensor_slices(model)
    with BatchSimulator(model, cfg.nthread) as sim:
        for off in np.atleast_2d(offsets_m):
            ball = ball0 + off
            states, sensors = sim.run_with_sensors(
                scene.initial_scene_state(model, ball, first), ctrl[None])
            in_motion = dt * np.arange(1, nstep + 1) <= motion.duration_s
            margin = support_margin_batch(sensors[0], sl)
            out["min_margin_m"].append(float(np.min(margin[in_motion])))
            qb = nao.state_qpos(model, states[0, -1], scene.BALL_JOINT, 2)
            vb = nao.state_qvel(model, states[0, -1], scene.BALL_JOINT, 2)
            travel = qb + vb * np.linalg.norm(vb) / (2 * decel) - ball
            fell = fall_step(torso_track(states), cfg.fall_height_m, cfg.fall_tilt_rad)[0]
            out["distance_m"].append(travel[0])
            out["lateral_m"].append(travel[1])
            out["fell"].append(float(fell < nstep))
            out["exec_time_s"].append(motion.duration_s)
    return {k: np.array(v) for k, v in out.items()}
