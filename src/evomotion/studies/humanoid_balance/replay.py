"""``evomotion replay RUN`` for a humanoid-balance run: its best policy played on its robot.

The problem is rebuilt from the run folder's ``config.toml`` and ``policy.npz`` is read back
(:func:`.compare.load_run`). One episode of the run's task is played in the unseen world of
``seed`` (:data:`.compare.EVAL_SEED_BASE`, so ``compare --seed S`` starts with the same world)
and reported as ``evomotion replay FILE.motion`` reports a motion; ``--stress N`` plays N such
worlds (that one first) and prints the survival; ``--video`` renders the first world, the push
included (the model drawn is the nominal one: masses and friction do not show).
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from evomotion.sim.replay_report import report_replay
from evomotion.studies.humanoid_balance.compare import (
    MAX_WORLDS,
    check_options,
    eval_seeds,
    load_run,
    play_policy,
)


def replay_policy(path: str | Path, stress: int | None = None, seed: int = 0,
                  push_ns: float | None = None, video: str | Path | None = None
                  ) -> tuple[dict[str, Any], str | None]:
    """(summary, the reason the video was skipped or ``None``) of the policy of a run."""
    from evomotion.core.checks import check_number
    from evomotion.outfile import check_target
    from evomotion.sim.render import RenderUnavailableError, render_video
    from evomotion.sim.state import QPOS_OFFSET
    from evomotion.studies.humanoid_balance.episodes import push_range

    check_options(1, push_ns, seed)
    if stress is not None:
        check_number("--stress", stress, lo=1, hi=MAX_WORLDS, integer=True)
    if video is not None:
        video = check_target(video, "video")
    problem, policy, folder = load_run(path, "replay")
    scaled = None if push_ns is None else push_range(problem.robot, push_ns, push_ns)[0]
    seeds = eval_seeds(stress or 1, seed)
    ep = play_policy(problem, policy, seeds, scaled, record_states=video is not None)
    world = problem.worlds(seeds[:1], scaled)[0]
    fell = bool(ep.survived[0] == 0)
    summary: dict[str, Any] = {
        "run": str(folder), "robot": problem.robot.name, "duration_s": problem.cfg.duration_s,
        "push_ns": [float(v) for v in world.push_ns], "push_time_s": world.push_time_s,
        "fell": fell, "fall_time_s": float(ep.time_up_s[0]) if fell else None,
        "tilt_rad": float(ep.tilt_rad[0])}
    if stress:
        summary.update(stress=int(stress), seed=int(seed),
                       survival=float(ep.survived.mean()),
                       time_up_mean_s=float(ep.time_up_s.mean()))
    skipped = None
    if video is not None:
        states = ep.result.states
        assert states is not None
        qpos = states[0, :, QPOS_OFFSET:QPOS_OFFSET + problem.robot.model.nq]
        try:
            render_video(qpos, ep.result.control_dt_s, video, robot=problem.robot)
        except RenderUnavailableError as exc:
            skipped = str(exc)
    problem.sim.close()
    return summary, skipped


def played(run_dir: str | Path, world: int = 0, push_ns: float | None = None) -> Any:
    """The run's exported policy in unseen world ``world`` (the ``world``-th of ``compare
    --seed 0``; ``push_ns``: every push that many N s, ``None``: the world's own) as the
    studio's 3D player shows it (:class:`~evomotion.studies.view.Played`): the states every
    control period up to the fall, the targets sent (in force ``latency`` later)."""
    from evomotion.core.checks import check_number
    from evomotion.studies.humanoid_balance.episodes import push_range
    from evomotion.studies.view import Played

    check_options(1, push_ns, 0)
    check_number("world", world, lo=0, hi=MAX_WORLDS - 1, integer=True)
    problem, policy, _ = load_run(run_dir, "run")
    try:
        scaled = None if push_ns is None else push_range(problem.robot, push_ns, push_ns)[0]
        seeds = eval_seeds(int(world) + 1, 0)[-1:]
        ep = play_policy(problem, policy, seeds, scaled, record_states=True)
        w = problem.worlds(seeds, scaled)[0]
        res, sim = ep.result, problem.sim
    finally:
        problem.sim.close()
    assert res.states is not None and res.targets is not None
    n = int(np.ceil(res.steps[0] / sim.k)) + 1  # up to the fall (then the state repeats)
    # the targets sent after each state; the last state keeps the last ones (n >= 2: at least
    # one control step is simulated)
    full = sim.full_targets(res.targets[0, np.minimum(np.arange(n), n - 2)])
    push = np.asarray(w.push_ns, float)
    fell = bool(res.fell[0])
    caption = (f"unseen world {int(world)}: a {np.linalg.norm(push):.2f} N s push toward "
               f"{np.degrees(np.arctan2(push[1], push[0])):.0f}° (0° = the way it faces) at "
               f"{w.push_time_s:.2f} s; " +
               (f"fell at {float(res.fall_time_s[0]):.2f} s" if fell else
                f"stayed up for {problem.cfg.duration_s:g} s"))
    return Played(res.states[0, :n], full, res.control_dt_s,
                  float(res.fall_time_s[0]) if fell else None, caption)


def replay_policy_command(path: Path, json_out: bool = False, video: Path | None = None,
                          stress: int | None = None, seed: int = 0,
                          push_ns: float | None = None) -> None:
    """CLI body of ``evomotion replay RUN`` for a policy run (JSON only with ``json_out``)."""
    summary, skipped = replay_policy(path, stress, seed, push_ns, video)
    done, video = report_replay(summary, skipped, video, json_out)
    if done:
        return
    p = np.asarray(summary["push_ns"])
    state = f"fell at {summary['fall_time_s']:.2f} s" if summary["fell"] else "stayed up"
    print(f"{summary['robot']} policy of {Path(summary['run']).name}: pushed "
          f"{np.linalg.norm(p):.2f} N s toward {np.degrees(np.arctan2(p[1], p[0])):+.0f} deg "
          f"at {summary['push_time_s']:.2f} s, {state} "
          f"(mean tilt {np.degrees(summary['tilt_rad']):.1f} deg)")
    if "stress" in summary:
        print(f"{summary['stress']} perturbed worlds (seed {summary['seed']}): survival "
              f"{100 * summary['survival']:.0f}%, fall rate {100 * (1 - summary['survival']):.0f}"
              f"%, mean time up {summary['time_up_mean_s']:.2f} s of {summary['duration_s']:g}")
    if video is not None:
        print(f"video: {video}")
