"""Replay a Webots ``.motion`` on the NAO model and measure what it did.

Webots' motion player sets every motor target to the linear interpolation of the two
surrounding poses at each control step (before the first pose: the first pose; after the
last: the last pose). Here the same targets are precomputed for every physics step and the
motion is played open loop with :mod:`mujoco.rollout`. The robot starts at rest in the
motion's first pose (joints the motion does not name hold :data:`~evomotion.sim.nao.INITIAL_POSE`),
feet on the floor, facing +x. ``*`` values are skipped: a joint is interpolated between its
defined poses only. After the motion the last pose is held for ``hold_s`` seconds. Falls use
the thresholds of :mod:`evomotion.sim.nao.constants`. :func:`replay_command` is the body of
``evomotion replay``.
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

import numpy as np

from evomotion.sim import nao
from evomotion.sim.nao.motion import Motion, read_motion
from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track


def motion_targets(motion: Motion, dt: float, nstep: int) -> tuple[np.ndarray, np.ndarray]:
    """(first pose[22], controls[nstep, 22]) for the model's actuators (``nao.JOINTS``)."""
    base = nao.pose_vector()
    t_s = motion.times_ms / 1000.0
    t = dt * np.arange(nstep)  # the target applied during physics step i (from t = i dt)
    ctrl = np.tile(base, (nstep, 1))
    first = base.copy()
    for j, name in enumerate(nao.JOINTS):
        if name not in motion.joints:
            continue
        col = motion.column(name)
        ok = ~np.isnan(col)
        if not ok.any():
            continue
        ctrl[:, j] = np.interp(t, t_s[ok], col[ok])
        first[j] = col[ok][0]
    return first, ctrl


def simulate_motion(motion: Motion, hold_s: float = 1.0, nthread: int = 1) -> dict:
    """Play ``motion`` and return the summary plus the trajectory (``qpos``, ``dt``)."""
    model = nao.load_model()
    dt = float(model.opt.timestep)
    nstep = int(np.ceil((motion.duration_s + hold_s) / dt))
    first, ctrl = motion_targets(motion, dt, nstep)
    with BatchSimulator(model, nthread) as sim:
        states = sim.run(nao.initial_state(model, first), ctrl[None])
    track = torso_track(states)
    fall = int(fall_step(track, nao.FALL_HEIGHT_M, nao.FALL_TILT_RAD)[0])
    d = track.xyz[0, -1, :2] - nao.state_qpos(model, states[0, 0], nao.ROOT_JOINT, 2)
    summary = {
        "displacement_m": [float(d[0]), float(d[1])],
        "heading_change_rad": float(track.yaw_rad[0, -1] - track.yaw_rad[0, 0]),
        "fell": fall < nstep,
        "fall_time_s": float((fall + 1) * dt) if fall < nstep else None,
    }
    return {"summary": summary, "qpos": nao.state_qpos_all(model, states[0]), "dt": dt,
            "model": model}


def replay(path: str | Path, video: str | Path | None = None, hold_s: float = 1.0) -> dict:
    """Replay a ``.motion`` file: ``{"displacement_m": [dx, dy], "heading_change_rad": h,
    "fell": bool, "fall_time_s": t or None}``; optionally render an MP4 to ``video``."""
    result = simulate_motion(read_motion(path), hold_s=hold_s)
    if video is not None:
        from evomotion.sim.render import render_video

        render_video(result["qpos"], result["dt"], video)
    return result["summary"]


def replay_command(path: Path, json_out: bool = False, video: Path | None = None) -> None:
    """CLI body of ``evomotion replay``: JSON only on stdout with ``json_out``. Without a GL
    backend the video is skipped with a note on stderr."""
    from evomotion.sim.render import RenderUnavailableError

    try:
        summary = replay(path, video=video)
    except RenderUnavailableError as exc:
        print(f"video skipped: {exc}", file=sys.stderr)
        summary, video = replay(path), None
    if json_out:
        print(json.dumps(summary))
        return
    dx, dy = summary["displacement_m"]
    state = f"fell at {summary['fall_time_s']:.2f} s" if summary["fell"] else "stayed up"
    print(f"{Path(path).name}: moved dx={dx:+.3f} m dy={dy:+.3f} m, "
          f"turned {np.degrees(summary['heading_change_rad']):+.1f} deg, {state}")
    if video is not None:
        print(f"video: {video}")
