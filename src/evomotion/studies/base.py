"""The study descriptor: how a study plugs into the runner and the CLI."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from evomotion.core.problem import Problem
from evomotion.run.context import RunContext


@dataclass(frozen=True)
class Study:
    """A study: problem factory, typed problem config, defaults and optional hooks.

    - ``problem_config``: a frozen dataclass type; its defaults are the study's defaults and
      it must be picklable (process/Ray workers rebuild the problem from it).
    - ``make_problem(problem_cfg)`` builds the :class:`Problem` (once per worker).
    - ``defaults``: overrides of the generic sections, e.g.
      ``{"algorithm": {"pop_size": 100, "crossover": "blx_alpha"}, "run": {"generations": 60}}``.
    - ``on_checkpoint(ctx)``: called every ``run.checkpoint_every`` generations (for example
      to write ``best.motion``); ``finalize(ctx)`` once at the end (plots, videos, best.json).
    - ``cli``: a ``typer.Typer`` with the study's own subcommands (``evomotion <name> ...``).
    - ``run``: a custom driver ``run(config, out_dir, evaluator_name, quiet) -> int`` replacing
      the generic ask/tell loop (for search-based or multi-phase studies).
    """

    name: str
    description: str
    problem_config: type
    make_problem: Callable[[Any], Problem]
    defaults: dict[str, dict[str, Any]] = field(default_factory=dict)
    on_checkpoint: Callable[[RunContext], None] | None = None
    finalize: Callable[[RunContext], None] | None = None
    cli: Any = None
    run: Callable[..., int] | None = None
