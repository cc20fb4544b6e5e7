"""The run loop's declared contracts: what it calls on its subscribers, studies and problems.

Every optional hook the loop may call is declared here once, as a :class:`typing.Protocol`
(``runtime_checkable`` where the loop asks whether an object has it), so that a study or a
problem that offers it is type-checked against it, and the loop never looks a hook up by name.
The subscriber events follow EvoTorch's searcher hooks (``before_step_hook``,
``after_step_hook``, ``end_of_run_hook``; Toklu et al. 2023, *EvoTorch: Scalable Evolutionary
Computation in Python*, arXiv:2302.12600), made explicit per event.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from contextlib import AbstractContextManager
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Protocol, runtime_checkable

import numpy as np

from evomotion.core.problem import MeasureSpec
from evomotion.run.context import RunContext

if TYPE_CHECKING:
    from evomotion.run.run_state import RunState, StepRecord


class Subscriber(Protocol):
    """An observer of the run loop (:mod:`evomotion.run.loop`); every event is optional
    (a subclass overrides the ones it needs). Subscribers are called in the order they were
    given, for every event.

    - ``on_start(run)``: the loop is about to take its first step (new or resumed run);
    - ``on_step(run, step)``: a step is done, its stop reason known;
    - ``on_checkpoint(run)``: a periodic checkpoint is due (every ``run.checkpoint_every``);
    - ``on_close(run)``: the loop has ended, however it ended (a stop, Ctrl-C, a crash);
    - ``on_finish(ctx, code)``: the finishing phase (final artifacts) of a run with a folder;
      returns the run's exit code (``code`` unless the subscriber changes it).
    """

    def on_start(self, run: RunState) -> None:
        return None

    def on_step(self, run: RunState, step: StepRecord) -> None:
        return None

    def on_checkpoint(self, run: RunState) -> None:
        return None

    def on_close(self, run: RunState) -> None:
        return None

    def on_finish(self, ctx: RunContext, code: int) -> int:
        return code



@dataclass(frozen=True)
class Replay:
    """A motion played on a study's robot, for the loggers (``run.loggers = ["rerun"]``):
    ``qpos[T, nq]`` of the MuJoCo model ``model`` every ``dt`` seconds; ``root_body`` is the
    body whose path is drawn (the torso)."""

    model: Any
    dt: float
    qpos: np.ndarray
    root_body: int


#: a study's artifact hook (``on_checkpoint``, ``finalize``, ``best_record``, ``replay``)
ArtifactHook = Callable[[RunContext], Any]
#: the context a study's artifact hooks run in (e.g. rendering off for ``run.videos = false``)
ArtifactScope = Callable[[RunContext], AbstractContextManager[None]]
#: a study's replay of its best motion on its robot, for the loggers
ReplayHook = Callable[[RunContext], Replay | None]
#: ``algorithm.name -> (config dataclass, factory(problem, config) -> Driver)``
StudyAlgorithms = Mapping[str, tuple[type, Callable[..., Any]]]


class RunRecord(Protocol):
    """What a run ran on, kept in the run folder as ``name`` (e.g. ``physics.json``: the
    physics backend) at every start and resume; a resume on something else is noted."""

    @property
    def name(self) -> str: ...

    def record(self) -> dict[str, Any]:
        """The record now."""
        ...

    def text(self, now: dict[str, Any]) -> str:
        """The file's text for the record ``now``."""
        ...

    def start_note(self, now: dict[str, Any]) -> str | None:
        """A line for the run log when the run (re)starts, or ``None``."""
        ...

    def resume_note(self, before: Any, now: dict[str, Any]) -> str | None:
        """A line for the run log when the record the run folder holds (``before``: the JSON
        read back, ``None`` when unreadable) differs from ``now``, or ``None``."""
        ...


class LoopStudy(Protocol):
    """What the run loop reads of every study: its name, how a problem is built (once per
    worker) and its own methods."""

    @property
    def name(self) -> str: ...

    @property
    def make_problem(self) -> Callable[[Any], Any]: ...

    @property
    def algorithms(self) -> StudyAlgorithms: ...


@runtime_checkable
class RunStudy(LoopStudy, Protocol):
    """A study that runs into a run folder (:class:`evomotion.studies.base.Study`): its
    artifact hooks, each optional (``None``)."""

    @property
    def on_checkpoint(self) -> ArtifactHook | None: ...

    @property
    def finalize(self) -> Callable[[RunContext], int | None] | None: ...

    @property
    def best_record(self) -> Callable[[RunContext], dict[str, Any]] | None: ...

    @property
    def artifact_scope(self) -> ArtifactScope | None: ...

    @property
    def replay(self) -> ReplayHook | None: ...

    @property
    def run_record(self) -> Callable[[Any], RunRecord | None] | None: ...


# --- optional hooks of a problem config (``config.problem``) ---------------------------------

@runtime_checkable
class SeededByRun(Protocol):
    """A problem config whose randomness (e.g. perturbed worlds) is drawn from the run seed:
    ``with_run_seed(seed)`` returns the config the run uses."""

    def with_run_seed(self, seed: int) -> Any: ...


@runtime_checkable
class ConfigForWorker(Protocol):
    """A problem config that says how a one-core worker (process, Ray, Dask) builds its
    problem: ``for_worker()`` returns that config (e.g. one rollout thread)."""

    def for_worker(self) -> Any: ...


@runtime_checkable
class SizedGenome(Protocol):
    """A problem config that tells its genome's length before the problem is built."""

    def genome_dim(self) -> int: ...


@runtime_checkable
class EstimatesMemory(Protocol):
    """A problem config that estimates the bytes its simulation of a population needs."""

    def memory_bytes(self, pop_size: int) -> int: ...


@runtime_checkable
class NamesMemoryKeys(Protocol):
    """The ``[problem]`` fields :meth:`EstimatesMemory.memory_bytes` depends on (named in
    the message when a run would not fit)."""

    memory_keys: tuple[str, ...]


@runtime_checkable
class SelfChecking(Protocol):
    """A config section with its own checks beyond the field types: ``validate()`` raises
    ``ValueError`` (or :class:`~evomotion.errors.InputError`) naming the key."""

    def validate(self) -> None: ...


# --- optional hooks of a problem --------------------------------------------------------------

@runtime_checkable
class ContextRows(Protocol):
    """A problem whose evaluation rows carry more than the genome (a policy search's
    observation normaliser and episode seeds, :mod:`evomotion.studies.policy_search`): its
    driver builds the rows; ``evaluation_rows(genomes)`` gives rows with a neutral context
    (for checks that evaluate genomes directly)."""

    def evaluation_rows(self, genomes: Any) -> Any: ...


@runtime_checkable
class EstimatesDeviceMemory(Protocol):
    """A GPU-backend problem: ``device_memory(pop_size) -> (needed, free, device)`` of one
    batch, or ``None`` (free ``None``: unknown)."""

    def device_memory(self, pop_size: int) -> tuple[int, int | None, str] | None: ...


@runtime_checkable
class OwnMutation(Protocol):
    """A problem with its own mutation (e.g. one that keeps a path valid)."""

    def mutate(self, x: np.ndarray, rng: np.random.Generator, rate: float) -> np.ndarray: ...


@runtime_checkable
class OwnInitialPopulation(Protocol):
    """A problem that draws its own initial population of ``n`` genomes."""

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray: ...


@runtime_checkable
class HasMeasures(Protocol):
    """A quality-diversity problem: its behaviour descriptors (``None``: it has none)."""

    measure_spec: MeasureSpec | None


class ConfiguredStudy(Protocol):
    """What the config resolver reads of a study (:func:`evomotion.run.config.
    resolve_config`): its ``[problem]`` dataclass, its defaults and presets (sections of
    overrides), its defaults per bundled robot (over the defaults), the registered optimizers
    it accepts (``None``: all), its own methods and the keys it moved (``{"problem.method":
    "algorithm.method"}``: old place -> new place)."""

    @property
    def name(self) -> str: ...

    @property
    def problem_config(self) -> type: ...

    @property
    def defaults(self) -> Mapping[str, Mapping[str, Any]]: ...

    @property
    def presets(self) -> Mapping[str, Mapping[str, Mapping[str, Any]]]: ...

    @property
    def robot_defaults(self) -> Mapping[str, Mapping[str, Mapping[str, Any]]]: ...

    @property
    def defaults_key(self) -> str: ...

    @property
    def robot_presets(self) -> Mapping[str, Mapping[str, Mapping[str, Mapping[str, Any]]]]: ...

    @property
    def defaults_alias(self) -> Callable[[str], str] | None: ...

    @property
    def algorithm_tunings(self) -> Mapping[str, Mapping[str, Any]]: ...

    @property
    def core_algorithms(self) -> tuple[str, ...] | None: ...

    @property
    def algorithms(self) -> StudyAlgorithms: ...

    @property
    def moved_keys(self) -> Mapping[str, str]: ...
