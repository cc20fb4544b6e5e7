"""The study descriptor: how a study plugs into the run loop and the CLI."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from evomotion.run.context import RunContext
from evomotion.run.contracts import ArtifactScope, ReplayHook, RunRecord, StudyAlgorithms
from evomotion.studies.run_hooks import motion_replay, physics_run_record, videos_scope
from evomotion.studies.view import StudyView


@dataclass(frozen=True)
class Study:
    """A study: problem factory, typed problem config, defaults, presets and optional hooks.

    - ``problem_config``: a frozen dataclass type; its defaults are the study's defaults and
      it must be picklable (process/Ray workers rebuild the problem from it).
    - ``make_problem(problem_cfg)`` builds the :class:`~evomotion.core.problem.Problem` (once
      per worker; a study with its own ``algorithms`` may build another kind, a search's
      state space).
    - ``defaults``: the study's best-known setting, as overrides of the sections, e.g.
      ``{"algorithm": {"pop_size": 100, "crossover": "blx_alpha"}, "run": {"generations": 60}}``.
    - ``presets``: named settings over the defaults (``--preset paper``: the paper's literal
      setting), same form as ``defaults``; ``preset_notes`` says in one line what each is.
    - ``robot_defaults``: the best-known setting on another robot, ``robot -> sections``
      (same form as ``defaults``), layered over ``defaults`` when ``problem.robot`` is that
      bundled robot (``--robot dm-humanoid``; ``""``: no robot given, the study's own); a
      preset, a file or ``--set`` still wins. ``defaults_key`` names the problem key whose
      value picks them: ``"robot"``, or another (``gym``: ``"env"``, the environment's id).
    - ``robot_presets``: a preset's setting on another robot (``gym``: environment), ``preset
      -> robot -> sections``, layered over that preset when ``problem.<defaults_key>`` names
      the robot (``gym --preset paper``: the paper's hyperparameters of each task).
    - ``defaults_alias``: the key of ``robot_defaults`` and ``robot_presets`` a value of
      ``problem.<defaults_key>`` reads (``gym``: any version of a task, ``Walker2d-v4``, reads
      its v5 id's); ``None``: the value itself.
    - ``algorithm_tunings``: ``name -> [algorithm] keys`` for a method that is not the default,
      used when the user picks it (``gym``: CMA-ES's step size in the policy's units); a
      default's own tuning that a robot's defaults or a preset replaced is kept the same way.
    - ``preset_studies``: presets that are another registered study, ``name -> study``
      (``humanoid-walk --preset open-loop`` runs ``humanoid-walk-open-loop``, a problem of
      another kind); ``preset_notes`` says what each is.
    - ``core_algorithms``: the registered optimizers the study accepts (``None``: all of them).
    - ``algorithms``: the study's own methods, ``name -> (config dataclass, factory(problem,
      config) -> Driver)``, for methods that are not plain ask/tell (a multi-phase schedule, a
      search); their config is the ``[algorithm]`` section like any optimizer's.
    - ``on_checkpoint(ctx)``: called every ``run.checkpoint_every`` steps and at the end (for
      example to write ``best.motion``); ``finalize(ctx)`` once at the end of a run that was not
      interrupted (plots, videos); it may return an exit code (e.g. 3: not solved).
    - ``best_record(ctx) -> dict``: the study's own ``best.json`` keys (after the envelope).
    - ``artifact_scope(ctx)``: the context manager the artifact hooks run in (default:
      rendering off for ``run.videos = false``, :func:`~evomotion.studies.run_hooks.
      videos_scope`).
    - ``replay(ctx) -> Replay | None``: the best motion played on the study's robot, for the
      rerun logger (default: ``best.motion`` on the problem's ``robot``,
      :func:`~evomotion.studies.run_hooks.motion_replay`).
    - ``run_record(problem) -> RunRecord | None``: what the run runs on, recorded in the run
      folder (default: ``physics.json`` of a problem that simulates,
      :func:`~evomotion.studies.run_hooks.physics_run_record`).
    These hooks are the run loop's contracts (:mod:`evomotion.run.contracts`).
    - ``replay_run(path, *, json_out, video, stress, seed, push_ns)``: ``evomotion replay RUN``
      for a run of this study (a policy played in unseen episodes or worlds; ``None``: the
      study's runs are replayed through their ``.motion`` files).
    - ``cli``: a ``typer.Typer`` with the study's own subcommands (``evomotion <name> ...``).
    - ``view``: what the studio shows of a run (:class:`~evomotion.studies.view.StudyView`;
      ``None``: its curves only).
    - ``smoke``: ``--set`` items that make a run of a few seconds (the conformance tests and
      ``benchmarks/run_loop_table.py`` use them; a user can too, to check an installation).
    - ``moved_keys``: keys the study moved, old place -> new place (``{"problem.method":
      "algorithm.method"}``); a config with the old one is read at the new place with a note
      (:mod:`evomotion.run.moved_keys`: files, ``--set``, run folders on resume).
    """

    name: str
    description: str
    problem_config: type
    make_problem: Callable[[Any], Any]
    defaults: dict[str, dict[str, Any]] = field(default_factory=dict)
    presets: dict[str, dict[str, dict[str, Any]]] = field(default_factory=dict)
    preset_notes: dict[str, str] = field(default_factory=dict)
    preset_studies: dict[str, str] = field(default_factory=dict)
    robot_defaults: dict[str, dict[str, dict[str, Any]]] = field(default_factory=dict)
    defaults_key: str = "robot"
    robot_presets: dict[str, dict[str, dict[str, dict[str, Any]]]] = field(default_factory=dict)
    defaults_alias: Callable[[str], str] | None = None
    algorithm_tunings: dict[str, dict[str, Any]] = field(default_factory=dict)
    core_algorithms: tuple[str, ...] | None = None
    algorithms: StudyAlgorithms = field(default_factory=dict)
    on_checkpoint: Callable[[RunContext], None] | None = None
    finalize: Callable[[RunContext], int | None] | None = None
    best_record: Callable[[RunContext], dict[str, Any]] | None = None
    artifact_scope: ArtifactScope | None = videos_scope
    replay: ReplayHook | None = motion_replay
    run_record: Callable[[Any], RunRecord | None] | None = physics_run_record
    replay_run: Callable[..., None] | None = None
    cli: Any = None
    smoke: tuple[str, ...] = ()
    view: StudyView | None = None
    moved_keys: dict[str, str] = field(default_factory=dict)


def lazy_hook(module: str, name: str) -> Callable[[RunContext], Any]:
    """A study hook that imports ``module`` (and its heavy dependencies: rendering, export)
    only when the run loop first calls it; the wrapper carries the hook's name for the
    run log's warnings."""

    def hook(ctx: RunContext) -> Any:
        import importlib

        return getattr(importlib.import_module(module), name)(ctx)

    hook.__name__ = hook.__qualname__ = name
    hook.module = module  # type: ignore[attr-defined]  # what it imports, for preloading
    return hook
