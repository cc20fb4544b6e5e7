"""``evomotion replay RUN`` for a humanoid-walk run: its controller walked under a command.

The command is ``--command vx,vy,w`` (held, ramped from standing over the run's ``ramp_s``), a
command file (``--command FILE``: lines ``t_s, vx, vy, w``, a new command from each time on,
ramped as in training; ``#`` starts a comment), or by default the run's random schedule of the
unseen world. One episode (``--duration`` s, default 20) is played in the unseen world of
``seed`` (the worlds of ``compare --seed S`` start with it: perturbed, one push, ``--push P``
fixing its size); ``--stress N`` plays N such worlds and prints the survival; ``--video``
renders the first (the nominal model is drawn: masses and friction do not show).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.sim.replay_report import report_replay

MAX_WORLDS = 10_000
MAX_FILE_LINES = 10_000


def read_command_file(path: Path) -> tuple[np.ndarray, np.ndarray]:
    """(times ``[K]`` s, commands ``[K, 3]``) of a command file; one-line errors naming the
    line."""
    from evomotion.textio import read_text_lines

    lines = read_text_lines(path, "command file")
    times: list[float] = []
    cmds: list[list[float]] = []
    for i, line in enumerate(lines, 1):
        line = line.split("#", 1)[0].strip()
        if not line:
            continue
        parts = [p for p in line.replace(",", " ").split() if p]
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            vals = []
        if len(vals) != 4 or not all(math.isfinite(v) for v in vals):
            raise InputError(f"{path}:{i}: expected 't_s, vx, vy, w' (four finite numbers), "
                             f"got {line[:60]!r}")
        if times and vals[0] <= times[-1]:
            raise InputError(f"{path}:{i}: times must increase ({vals[0]:g} after "
                             f"{times[-1]:g})")
        if vals[0] < 0 or len(times) >= MAX_FILE_LINES:
            raise InputError(f"{path}:{i}: a time >= 0 and at most {MAX_FILE_LINES} commands "
                             "expected")
        times.append(vals[0])
        cmds.append(vals[1:])
    if not times:
        raise InputError(f"{path}: no command in the file (lines 't_s, vx, vy, w')")
    return np.array(times), np.array(cmds)


def parse_command(text: str) -> tuple[np.ndarray, np.ndarray]:
    """``--command``: ``vx,vy,w`` (held from 0 s) or the path of a command file."""
    parts = [p.strip() for p in text.split(",")]
    if len(parts) == 3:
        try:
            vals = [float(p) for p in parts]
        except ValueError:
            vals = []
        if len(vals) == 3:
            if not all(math.isfinite(v) for v in vals):
                raise InputError(f"--command {text}: expected three finite numbers vx,vy,w")
            return np.zeros(1), np.array([vals])
    path = Path(text)
    if not path.is_file():
        raise InputError(f"--command {text!r}: expected vx,vy,w (m/s, m/s, rad/s) or a command "
                         "file of lines 't_s, vx, vy, w'")
    return read_command_file(path)


def ramped(times: np.ndarray, cmds: np.ndarray, t: np.ndarray, ramp_s: float) -> np.ndarray:
    """The commands ``[T, 3]`` at ``t``: each new one reached linearly over ``ramp_s`` from the
    previous (the first from standing), as training's schedules."""
    seg = np.searchsorted(times, t, side="right") - 1
    prev = np.where((seg > 0)[:, None], cmds[np.maximum(seg - 1, 0)], 0.0)
    now = np.where((seg >= 0)[:, None], cmds[np.maximum(seg, 0)], 0.0)
    frac = np.clip((t - times[np.maximum(seg, 0)]) / ramp_s, 0.0, 1.0)[:, None]
    return np.where((seg >= 0)[:, None], prev + (now - prev) * frac, 0.0)


def replay_walk(path: str | Path, stress: int | None = None, seed: int = 0,
                push_ns: float | None = None, video: str | Path | None = None,
                command: str | None = None, duration_s: float = 20.0
                ) -> tuple[dict[str, Any], str | None]:
    """(summary, the reason the video was skipped or ``None``) of a run's controller."""
    from evomotion.core.checks import check_number
    from evomotion.outfile import check_target
    from evomotion.sim.render import RenderUnavailableError, render_video
    from evomotion.sim.state import QPOS_OFFSET
    from evomotion.studies.episode_worlds import push_range
    from evomotion.studies.humanoid_omniwalk.commands import tracking
    from evomotion.studies.humanoid_omniwalk.compare import EVAL_SEED_BASE, load_run

    check_number("--seed", seed, lo=0, hi=2**20, integer=True)
    check_number("--duration", duration_s, lo=0.5, hi=600.0)
    if stress is not None:
        check_number("--stress", stress, lo=1, hi=MAX_WORLDS, integer=True)
    if push_ns is not None:
        check_number("--push", push_ns, lo=0.0, hi=1000.0)
    given = None if command is None else parse_command(command)
    if video is not None:
        video = check_target(video, "video")
    problem, policy, folder = load_run(path, duration_s, "replay")
    n = int(stress or 1)
    seeds = EVAL_SEED_BASE + int(seed) * MAX_WORLDS + np.arange(n)
    scaled = None if push_ns is None else push_range(problem.robot, push_ns, push_ns)[0]
    C = math.ceil(problem.nstep / problem.control_steps)
    t = np.arange(C) * problem.ctl.control_dt
    cmds = None if given is None else np.broadcast_to(
        ramped(*given, t, problem.cfg.ramp_s), (n, C, 3)).copy()
    m, res, cmds = problem.play(np.tile(policy.params, (n, 1)), np.tile(policy.obs_mean, (n, 1)),
                                np.tile(policy.obs_std, (n, 1)), seeds, scaled, cmds)
    tr = tracking(res.torso, cmds, problem.ctl.window, problem.ctl.control_dt)
    world = problem.worlds(seeds[:1], scaled)[0]
    fell = bool(res.fell[0])
    d = res.torso[0, -1, :2] - res.torso[0, 0, :2]
    summary: dict[str, Any] = {
        "run": str(folder), "robot": problem.robot.name, "duration_s": float(duration_s),
        "command": "random schedule" if command is None else command,
        "push_ns": [float(v) for v in world.push_ns], "push_time_s": world.push_time_s,
        "fell": fell, "fall_time_s": float(res.fall_time_s[0]) if fell else None,
        "distance_m": float(np.hypot(*d)),
        "speed_error_mps": float(m["speed_error_mps"][0]),
        "yaw_rate_error_dps": float(np.degrees(m["yaw_rate_error_rps"][0])),
        "mean_walked": {"vx_mps": float(tr.vx[0].mean()), "vy_mps": float(tr.vy[0].mean()),
                        "yaw_rate_dps": float(np.degrees(tr.yaw_rate[0].mean()))}}
    if stress:
        summary.update(stress=n, seed=int(seed), survival=float(m["survived"].mean()),
                       time_up_mean_s=float(m["time_up_s"].mean()))
    skipped = None
    if video is not None:
        assert res.states is not None
        qpos = res.states[0, :, QPOS_OFFSET:QPOS_OFFSET + problem.robot.model.nq]
        try:
            render_video(qpos, res.control_dt_s, video, robot=problem.robot)
        except RenderUnavailableError as exc:
            skipped = str(exc)
    problem.sim.close()
    return summary, skipped


def replay_walk_command(path: Path, json_out: bool = False, video: Path | None = None,
                        stress: int | None = None, seed: int = 0, push_ns: float | None = None,
                        command: str | None = None, duration_s: float | None = None) -> None:
    """CLI body of ``evomotion replay RUN`` for a humanoid-walk run."""
    summary, skipped = replay_walk(path, stress, seed, push_ns, video, command,
                                   20.0 if duration_s is None else duration_s)
    done, video = report_replay(summary, skipped, video, json_out)
    if done:
        return
    w = summary["mean_walked"]
    state = f"fell at {summary['fall_time_s']:.2f} s" if summary["fell"] else "stayed up"
    print(f"walk controller of {Path(summary['run']).name}, {summary['command']}, "
          f"{summary['duration_s']:g} s: {state}; walked {summary['distance_m']:.2f} m (mean vx "
          f"{w['vx_mps']:.2f}, vy {w['vy_mps']:.2f} m/s, {w['yaw_rate_dps']:.0f} deg/s); "
          f"tracking error {summary['speed_error_mps']:.3f} m/s, "
          f"{summary['yaw_rate_error_dps']:.1f} deg/s")
    if "stress" in summary:
        print(f"{summary['stress']} perturbed worlds (seed {summary['seed']}): survival "
              f"{100 * summary['survival']:.0f}%, mean time up {summary['time_up_mean_s']:.2f} "
              f"s of {summary['duration_s']:g}")
    if video is not None:
        print(f"video: {video}")
