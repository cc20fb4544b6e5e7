"""Replay a Webots ``.motion`` on the NAO model and measure what it did.

Webots' motion player sets every motor target to the linear interpolation of the two
surrounding poses at each control step (before the first pose: the first pose; after the
last: the last pose). Here the same targets are precomputed for every physics step and the
motion is played open loop with :mod:`mujoco.rollout`. The robot starts at rest in the
motion's first pose (joints the motion does not name hold
:data:`~evomotion.sim.robots.nao.INITIAL_POSE`),
feet on the floor, facing +x. ``*`` values are skipped: a joint is interpolated between its
defined poses only. After the motion the last pose is held for ``hold_s`` seconds. Falls use
the thresholds of :mod:`evomotion.sim.robots.nao.constants`. :func:`replay_command` is the body of
``evomotion replay``.

Stress tests (:class:`StressOptions`, ``evomotion replay --friction/--mass-scale/--push/--trials/
--from``) replay the motion in perturbed worlds (:mod:`evomotion.sim.worlds`): the nominal
world with the given fixed values, plus ``trials`` worlds drawn from
:class:`~evomotion.sim.worlds.Perturbation` with the run seed (the given values pinned).
``--from face-down|face-up`` starts the robot lying (torso rotated +-90 degrees about y, the
lowest collision geom resting on the floor, joints at the motion's first pose); then ``fell``
is a fall after the robot was first upright, and ``ended_upright`` says whether it stands at the
end (torso above the fall height, tilted less than the fall tilt). The heading of a lying torso
is ill-defined (its yaw is read from a quaternion pitched 90 degrees).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import mujoco
import numpy as np

from evomotion.core.checks import check_choice, check_number
from evomotion.outfile import check_target
from evomotion.sim.motion import Motion, read_motion
from evomotion.sim.play import keyframe_targets
from evomotion.sim.replay_report import report_replay
from evomotion.sim.robots import nao
from evomotion.sim.rollout import BatchSimulator, fall_step, torso_track
from evomotion.sim.worlds import Perturbation, draw_worlds, make_world, simulate_worlds

STARTS = ("standing", "face-down", "face-up")
MAX_TRIALS = 1000
MAX_HOLD_S = 60.0
MAX_SCALE = 100.0  # --friction, --mass-scale: at most this factor
MAX_PUSH_NS = 50.0  # |--push| (N s; 9.4 m/s on the 5.3 kg NAO, still a stable simulation)
_CHUNK_BYTES = 256 * 2**20  # states kept at once by a stress test


def motion_targets(motion: Motion, dt: float, nstep: int) -> tuple[np.ndarray, np.ndarray]:
    """(first pose[22], controls[nstep, 22]) for the model's actuators (``nao.JOINTS``):
    :func:`evomotion.sim.play.keyframe_targets` from the NAO's initial pose (channels that are
    not the NAO's, e.g. other robots' or LED channels, are ignored as Webots ignores them)."""
    return keyframe_targets(nao.JOINTS, nao.pose_vector(), motion, dt, nstep)


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


@dataclass(frozen=True)
class StressOptions:
    """The stress-test options of ``evomotion replay`` (``None``: not given).

    ``friction`` and ``mass_scale`` scale every geom's friction and every link's mass (and
    inertia); ``push_ns`` is a lateral impulse (N s, +y = to the robot's left) on the torso at
    mid-motion; ``trials`` random worlds are drawn from :class:`Perturbation` with ``seed``
    (the given values pinned); ``start`` is one of :data:`STARTS`."""

    friction: float | None = None
    mass_scale: float | None = None
    push_ns: float | None = None
    trials: int | None = None
    seed: int = 0
    start: str | None = None

    def validate(self) -> None:
        """One-line :class:`~evomotion.errors.InputError` for a bad value."""
        if self.friction is not None:
            check_number("--friction", self.friction, lo=0.0, lo_open=True, hi=MAX_SCALE)
        if self.mass_scale is not None:
            check_number("--mass-scale", self.mass_scale, lo=0.0, lo_open=True, hi=MAX_SCALE)
        if self.push_ns is not None:
            check_number("--push", self.push_ns, lo=-MAX_PUSH_NS, hi=MAX_PUSH_NS)
        if self.trials is not None:
            check_number("--trials", self.trials, lo=1, hi=MAX_TRIALS, integer=True)
        check_number("--seed", self.seed, lo=0, integer=True)
        if self.start is not None:
            check_choice("--from", self.start, STARTS)

    @property
    def active(self) -> bool:
        """Whether any stress option is given (else the plain replay runs)."""
        return any(v is not None for v in (self.friction, self.mass_scale, self.push_ns,
                                           self.trials, self.start))


def start_state(model: mujoco.MjModel, pose: np.ndarray, start: str = "standing",
                clearance_m: float = 0.0005) -> np.ndarray:
    """Initial ``STATE_SPEC`` state: standing (:func:`nao.initial_state`) or lying face down
    (torso rotated +90 degrees about y: its front, +x, points down) or face up (-90 degrees),
    at rest, joints at ``pose``, the lowest collision geom ``clearance_m`` above the floor."""
    check_choice("start", start, STARTS)
    check_number("clearance_m", clearance_m, lo=0.0, hi=nao.model.MAX_CLEARANCE_M)
    if start == "standing":
        return nao.initial_state(model, pose)
    data = mujoco.MjData(model)
    for name, value in zip(nao.JOINTS, pose, strict=True):
        data.joint(name).qpos = value
    data.ctrl[:] = pose
    a = np.pi / 2 if start == "face-down" else -np.pi / 2
    root = nao.qpos_address(model)
    data.qpos[root:root + 7] = [0.0, 0.0, 1.0, np.cos(a / 2), 0.0, np.sin(a / 2), 0.0]
    mujoco.mj_kinematics(model, data)
    floor = model.geom("floor").id
    gap = min(mujoco.mj_geomDistance(model, data, g, floor, 2.0, None)
              for g in range(model.ngeom) if model.geom_contype[g] and g != floor)
    data.qpos[root + 2] += clearance_m - gap
    mujoco.mj_forward(model, data)
    return nao.get_state(model, data)


def outcomes(model: mujoco.MjModel, states: np.ndarray, lying: bool = False) -> dict:
    """Per rollout of ``states[k, nstep, nstate]``: ``fall_step[k]`` (``nstep``: none; with
    ``lying``, only falls after the robot was first upright count), ``displacement_m[k, 2]``
    (from the state after the first step, as :func:`simulate_motion`), ``heading_change_rad[k]``
    and ``ended_upright[k]``."""
    track = torso_track(states)
    fallen = (track.xyz[..., 2] < nao.FALL_HEIGHT_M) | (track.up_z < np.cos(nao.FALL_TILT_RAD))
    counted = fallen & (np.cumsum(~fallen, axis=-1) > 0) if lying else fallen
    nstep = fallen.shape[-1]
    fall = np.where(counted.any(axis=-1), counted.argmax(axis=-1), nstep)
    return {"fall_step": fall,
            "displacement_m": track.xyz[:, -1, :2] - track.xyz[:, 0, :2],
            "heading_change_rad": track.yaw_rad[:, -1] - track.yaw_rad[:, 0],
            "ended_upright": ~fallen[:, -1]}


def stress_motion(motion: Motion, options: StressOptions, hold_s: float = 1.0,
                  nthread: int = 0) -> dict:
    """Play ``motion`` in the nominal perturbed world and in ``options.trials`` drawn worlds
    (one batch, in chunks that keep at most ~256 MB of states). Returns the summary (the plain
    keys for the nominal world, ``ended_upright`` with a ``start``, and with ``trials``:
    ``trials, fall_rate, forward_mean_m, forward_min_m``, plus ``upright_rate`` with a
    ``start``) and the nominal trajectory (``qpos``, ``dt``)."""
    options.validate()
    model = nao.load_model()
    dt = float(model.opt.timestep)
    nstep = int(np.ceil((motion.duration_s + hold_s) / dt))
    first, ctrl = motion_targets(motion, dt, nstep)
    start = options.start or "standing"
    init = start_state(model, first, start)
    friction = 1.0 if options.friction is None else float(options.friction)
    mass = 1.0 if options.mass_scale is None else float(options.mass_scale)
    push = 0.0 if options.push_ns is None else float(options.push_ns)
    mid = motion.duration_s / 2
    worlds = [make_world(model, friction_scale=friction, mass_scale=mass,
                         push_ns=(0.0, push, 0.0), push_time_s=mid)]
    if options.trials:
        pin: dict[str, Any] = ({"friction_scale": (friction, friction)}
                               if options.friction is not None else {})
        if options.mass_scale is not None:
            pin["mass_scale"] = (mass, mass)
        if options.push_ns is not None:
            pin.update(push_ns=(push, push), push_at=(0.5, 0.5))
        rng = np.random.default_rng(options.seed)
        worlds += draw_worlds(model, Perturbation(**pin), options.trials, rng, motion.duration_s)
    chunk = max(1, min(64, _CHUNK_BYTES // (8 * nstep * init.size)))
    parts, qpos = [], None
    for i in range(0, len(worlds), chunk):
        states = simulate_worlds(worlds[i:i + chunk], init, ctrl, nthread)
        assert isinstance(states, np.ndarray)  # without sensors: the states alone
        parts.append(outcomes(model, states, lying=start != "standing"))
        if qpos is None:
            qpos = nao.state_qpos_all(model, states[0]).copy()
    out = {key: np.concatenate([p[key] for p in parts]) for key in parts[0]}
    fall, d = out["fall_step"], out["displacement_m"]
    summary = {
        "displacement_m": [float(d[0, 0]), float(d[0, 1])],
        "heading_change_rad": float(out["heading_change_rad"][0]),
        "fell": bool(fall[0] < nstep),
        "fall_time_s": float((fall[0] + 1) * dt) if fall[0] < nstep else None,
    }
    if options.start is not None:
        summary["ended_upright"] = bool(out["ended_upright"][0])
    if options.trials:
        summary.update(trials=int(options.trials), fall_rate=float(np.mean(fall[1:] < nstep)),
                       forward_mean_m=float(d[1:, 0].mean()),
                       forward_min_m=float(d[1:, 0].min()))
        if options.start is not None:
            summary["upright_rate"] = float(np.mean(out["ended_upright"][1:]))
    return {"summary": summary, "qpos": qpos, "dt": dt}


def replay_motion(motion: Motion, video: str | Path | None = None, hold_s: float = 1.0,
                  stress: StressOptions | None = None) -> tuple[dict, str | None]:
    """Replay ``motion`` once (with active ``stress`` options, :func:`stress_motion`, else
    :func:`simulate_motion`) and render that replay to ``video`` when one is named. Returns
    the summary and, when no GL backend can render, the reason the video was skipped (the
    replay is not run again for it). ``video`` is checked before the simulation runs (an
    existing folder, not a device: :func:`evomotion.outfile.check_target`)."""
    from evomotion.sim.render import RenderUnavailableError, render_video

    check_number("--hold", hold_s, lo=0.0, hi=MAX_HOLD_S)
    if video is not None:
        video = check_target(video, "video")
    if stress is not None and stress.active:
        result = stress_motion(motion, stress, hold_s=hold_s)
    else:
        result = simulate_motion(motion, hold_s=hold_s)
    skipped = None
    if video is not None:
        try:
            render_video(result["qpos"], result["dt"], video)
        except RenderUnavailableError as exc:
            skipped = str(exc)
    return result["summary"], skipped


def replay(path: str | Path, video: str | Path | None = None, hold_s: float = 1.0,
           stress: StressOptions | None = None) -> dict:
    """Replay a ``.motion`` file: ``{"displacement_m": [dx, dy], "heading_change_rad": h,
    "fell": bool, "fall_time_s": t or None}`` (with active ``stress`` options, the keys of
    :func:`stress_motion`); optionally render an MP4 of the (nominal) replay to ``video``
    (:class:`~evomotion.sim.render.RenderUnavailableError` without a GL backend)."""
    from evomotion.sim.render import RenderUnavailableError

    summary, skipped = replay_motion(read_motion(path), video, hold_s, stress)
    if skipped is not None:
        raise RenderUnavailableError(skipped)
    return summary


def replay_command(path: Path, json_out: bool = False, video: Path | None = None,
                   hold_s: float = 1.0, stress: StressOptions | None = None) -> None:
    """CLI body of ``evomotion replay``: JSON only on stdout with ``json_out``. Without a GL
    backend the video is skipped with a note on stderr."""
    if stress is not None:
        stress.validate()
    if video is not None:
        video = check_target(video, "video")
    summary, skipped = replay_motion(read_motion(path), video, hold_s, stress)
    done, video = report_replay(summary, skipped, video, json_out)
    if done:
        return
    dx, dy = summary["displacement_m"]
    state = f"fell at {summary['fall_time_s']:.2f} s" if summary["fell"] else "stayed up"
    if "ended_upright" in summary:
        end = "ended upright" if summary["ended_upright"] else "ended not upright"
        lying = stress is not None and stress.start != "standing"
        fell = f"stood, then fell at {summary['fall_time_s']:.2f} s, " if summary["fell"] else ""
        state = fell + end if lying else f"{state}, {end}"
    print(f"{Path(path).name}: moved dx={dx:+.3f} m dy={dy:+.3f} m, "
          f"turned {np.degrees(summary['heading_change_rad']):+.1f} deg, {state}")
    if "trials" in summary and stress is not None:
        line = (f"{summary['trials']} perturbed trials (seed {stress.seed}): fall rate "
                f"{100 * summary['fall_rate']:.0f}%, forward mean "
                f"{summary['forward_mean_m']:+.3f} m, min {summary['forward_min_m']:+.3f} m")
        if "upright_rate" in summary:
            line += f", ended upright {100 * summary['upright_rate']:.0f}%"
        print(line)
    if video is not None:
        print(f"video: {video}")
