"""What the studio shows of a study's run: the study declares it, the studio draws it.

The studio knows no study by name. A :class:`~evomotion.studies.base.Study` carries a
:class:`StudyView` saying which of the studio's generic views apply to its runs (the run's
``.motion`` files played in 3D, a table from a JSON file, the quality-diversity archive's heat
map) and, for a 2-D study, a ``frames`` function that turns a run folder into a sequence of
matplotlib figures the studio steps through (a generation's population, a plan's states).

``frames`` receives a :class:`RunFiles`: the studio's bounded access to the run folder, so that
a study reads a run's files within the studio's memory and size limits without importing it.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from evomotion.core.problem import Problem


class NothingYetError(Exception):
    """The run has nothing to show yet; the message says what is missing (shown as is)."""


class RunFiles(Protocol):
    """A run folder as the studio lets a study's view read it (sizes bounded, files checked)."""

    run_dir: Path

    def history(self) -> list[tuple[int, np.ndarray, np.ndarray]]:
        """``(generation, population, fitness)`` per recorded generation of ``population.bin``;
        :class:`NothingYetError` when none is recorded."""
        ...

    def stats(self) -> dict[str, list[Any]]:
        """The columns of ``stats.csv`` (numbers, text or ``None`` per cell; empty when there
        is none yet)."""
        ...

    def problem(self) -> Problem:
        """The run's problem, built from its ``config.toml``."""
        ...

    def json(self, name: str, what: str) -> Any:
        """The JSON document ``name`` of the run folder (:class:`NothingYetError` when missing)."""
        ...


@dataclass(frozen=True)
class Frames:
    """A sequence the studio steps through: ``draw(k)`` gives frame ``k``'s figure (a
    matplotlib ``Figure``, closed by the studio) and its caption."""

    count: int
    draw: Callable[[int], tuple[Any, str]]
    label: str = "generation"
    title: str = ""


@dataclass(frozen=True)
class Scene:
    """A 3D scene of the study the studio plays motions in (the kick's: the NAO and its ball).

    ``load_model()`` gives the MuJoCo model (loaded once, shared, never modified);
    ``initial_state(model, pose)`` the full-physics state with the robot at rest in the
    motion's first ``pose``; ``look_x_m`` shifts the camera's target forward."""

    name: str
    load_model: Callable[[], Any]
    initial_state: Callable[[Any, np.ndarray], np.ndarray]
    look_x_m: float = 0.0


@dataclass(frozen=True)
class Played:
    """A closed-loop episode as the studio's 3D player shows it (no replay: a policy's motion
    is only what it did in that world): the full physics state ``states[T, ns]`` every
    ``frame_dt_s`` from the start, the servo targets in force after each ``ctrl[T, nu]``, when
    it fell (``None``: it stayed up) and a caption (the world, its push)."""

    states: np.ndarray
    ctrl: np.ndarray
    frame_dt_s: float
    fall_time_s: float | None
    caption: str = ""


@dataclass(frozen=True)
class StudyView:
    """The studio's views of a study's runs (all optional)."""

    motions: bool = False  # the run's .motion files, played in 3D on the run's robot
    scene: Scene | None = None  # the 3D scene of those motions (None: the run's robot alone)
    table: str | None = None  # a run file holding a JSON list of rows, shown as a table
    table_title: str = ""
    archive_map: bool = False  # the archive's heat map; a click plays that cell's motion
    #: an elite whose objective is at or below this fell (grey on the map, never played)
    archive_fallen_at: float | None = None
    frames: Callable[[RunFiles], Frames] | None = None
    #: ``genome_motion(problem, genome)``: a genome as a motion, so the studio replays the best
    #: of any generation recorded in ``population.bin`` (``run.history_every``)
    genome_motion: Callable[[Problem, np.ndarray], Any] | None = None
    #: the run's walk controller (policy.json with vx, vy, yaw_rate commands) driven live
    drive: bool = False
    #: ``played(run_dir, world, push_ns)``: the run's exported policy played in unseen world
    #: ``world`` (a push of ``push_ns`` N s, or ``None``: the world's own), a :class:`Played`
    played: Callable[[Path, int, float | None], Played] | None = None


def lazy(module: str, name: str) -> Callable[..., Any]:
    """The function ``name`` of ``module``, imported only when the studio first calls it (a
    view's matplotlib and drawing code, a scene's model)."""

    def call(*args: Any, **kwargs: Any) -> Any:
        import importlib

        return getattr(importlib.import_module(module), name)(*args, **kwargs)

    call.__name__ = call.__qualname__ = name
    return call
