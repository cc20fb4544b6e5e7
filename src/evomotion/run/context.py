"""What a study's artifact hooks receive from the runner."""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np


@dataclass
class RunContext:
    """A running (or finished) run as seen by a study's hooks.

    ``out_dir`` is the run folder; hooks write only inside it. ``log`` writes one line to
    the run's ``log.txt`` (and the console when not quiet).
    """

    study: str
    out_dir: Path | None
    config: Any  # the resolved top-level config dataclass (config.problem is the study's)
    problem: Any
    generation: int = 0
    evaluations: int = 0
    best_genome: np.ndarray | None = None
    best_fitness: float = float("nan")
    best_metrics: dict[str, float] = field(default_factory=dict)
    stop_reason: str | None = None
    log: Callable[[str], None] = print
    driver: Any = None  # the run's Driver (its final state is ``state``)
    state: Any = None
    cache: dict[str, Any] = field(default_factory=dict)  # hooks' shared results (one run)

    @property
    def plots_dir(self) -> Path:
        if self.out_dir is None:
            raise ValueError("a run without a folder has no plots folder")
        d = self.out_dir / "plots"
        d.mkdir(parents=True, exist_ok=True)
        return d
