"""The studies' default run-loop hooks: what the run loop may not know itself.

The run loop (:mod:`evomotion.run`) knows nothing of physics or robots; a
:class:`~evomotion.studies.base.Study` hands it these hooks (declared in
:mod:`evomotion.run.contracts`), each a default that a study may replace:

- :func:`videos_scope`: the context the study's artifact hooks run in; with
  ``run.videos = false`` no video is rendered (:func:`evomotion.sim.render.videos_off`);
- :func:`physics_run_record`: ``physics.json``, the physics backend a MuJoCo problem ran on
  and what it guarantees, compared on resume (a resume on other physics is not bit-identical);
- :func:`motion_replay`: the run's ``best.motion`` played on the problem's own robot, for the
  rerun logger.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from contextlib import contextmanager
from typing import Any, Protocol, runtime_checkable

import numpy as np

from evomotion.run.context import RunContext
from evomotion.run.contracts import Replay

PHYSICS_NAME = "physics.json"
#: what a resume compares of physics.json
PHYSICS_KEYS = ("backend", "device", "precision", "mujoco", "mujoco_warp", "deterministic",
                "robot", "robot_spec_sha256", "robot_mjcf_sha256", "numpy", "numpy_simd",
                "blas", "gymnasium", "env_backend")
#: physics.json's keys added later (the robot; the host's numpy, SIMD features and BLAS
#: kernels, sim/cpu_platform.py; gym's Gymnasium and how it is stepped): a run folder
#: written before lacks them
LATER_KEYS = ("robot", "robot_spec_sha256", "robot_mjcf_sha256", "numpy", "numpy_simd",
              "blas", "gymnasium", "env_backend")
MOTION_NAME = "best.motion"


@contextmanager
def videos_scope(ctx: RunContext) -> Iterator[None]:
    """Rendering off within the block when the run's ``run.videos`` is false."""
    if ctx.config.run.videos:
        yield
        return
    from evomotion.sim.render import videos_off

    with videos_off("videos are off (run.videos = false)"):
        yield


@runtime_checkable
class RecordsPhysics(Protocol):
    """A problem that simulates: ``physics_record()`` describes its backend
    (:func:`evomotion.sim.backend.physics_record`)."""

    def physics_record(self) -> dict[str, Any]: ...


class PhysicsRecord:
    """``physics.json`` of a problem that simulates (a :class:`~evomotion.run.contracts.
    RunRecord`)."""

    name = PHYSICS_NAME

    def __init__(self, problem: RecordsPhysics) -> None:
        self.problem = problem

    def record(self) -> dict[str, Any]:
        return self.problem.physics_record()

    def text(self, now: dict[str, Any]) -> str:
        return json.dumps(now, indent=1) + "\n"

    def start_note(self, now: dict[str, Any]) -> str | None:
        """A non-CPU backend is logged."""
        if now.get("backend") == "cpu":
            return None
        return (f"physics: backend {now['backend']} on {now.get('device', '?')}, "
                f"{now.get('precision', '?')}; {now.get('guarantee', '')}")

    def resume_note(self, before: Any, now: dict[str, Any]) -> str | None:
        """A resume on other physics than the run started on is noted (a key the run
        folder's record lacks was not recorded then)."""
        if not isinstance(before, dict):
            return None
        keys = tuple(k for k in PHYSICS_KEYS if k in before or k not in LATER_KEYS)
        if not any(before.get(k) != now.get(k) for k in keys):
            return None
        return (f"note: resumed on other physics than the run started on ({PHYSICS_NAME}: "
                f"{ {k: before.get(k) for k in keys if before.get(k) != now.get(k)} } -> "
                f"{ {k: now.get(k) for k in keys if before.get(k) != now.get(k)} }); the "
                "result is not bit-identical to an uninterrupted run")


def physics_run_record(problem: Any) -> PhysicsRecord | None:
    """The ``physics.json`` record of ``problem``, or ``None`` when it does not simulate."""
    return PhysicsRecord(problem) if isinstance(problem, RecordsPhysics) else None


@runtime_checkable
class HasRobot(Protocol):
    """A problem of a robot (:class:`evomotion.sim.robots.build.Robot`)."""

    robot: Any


def motion_replay(ctx: RunContext) -> Replay | None:
    """The run's ``best.motion`` played on the problem's robot (a problem without one is
    of the default robot, the NAO) and held for the problem's ``hold_s`` (1 s when it has
    none), as ``evomotion replay`` does; ``None`` when the run wrote no motion."""
    if ctx.out_dir is None:
        return None
    path = ctx.out_dir / MOTION_NAME
    if not path.exists():
        return None
    import mujoco

    from evomotion.sim.motion import read_motion
    from evomotion.sim.play import play_motion
    from evomotion.sim.robots import load_robot

    robot = ctx.problem.robot if isinstance(ctx.problem, HasRobot) else load_robot("nao")
    hold = float(getattr(getattr(ctx.problem, "cfg", None), "hold_s", 1.0))
    result = play_motion(robot, read_motion(path), hold_s=hold)
    model = robot.model
    free = np.flatnonzero(model.jnt_type == mujoco.mjtJoint.mjJNT_FREE)
    root = int(model.jnt_bodyid[free[0]]) if free.size else 1
    return Replay(model, float(result["dt"]), np.asarray(result["qpos"]), root)
