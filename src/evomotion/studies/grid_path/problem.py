"""The grid-path problem: batch fitness = path length + penalty per invalid segment.

Fitness (minimised), for the decoded polyline S, P_1..P_{n-1}, G::

    f = sum_i |P_{i+1} - P_i| + penalty * (number of invalid segments)

with ``penalty = width + height`` cells unless set (longer than any detour a valid path
makes on the map, so every valid path beats every invalid one of similar shape). The
paper's ``m`` sets the number of perpendiculars, ``n = floor(|SG| / (m sqrt 2))`` (see
:mod:`.encoding`); ``n_parts > 0`` overrides it (the "more perpendiculars" variant).

Validity uses the ``"closed"`` rule (centres model) in ``discrete`` mode and the ``"open"``
rule (free model) in ``continuous`` mode unless ``rule`` says otherwise.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from importlib import resources
from pathlib import Path

import numpy as np

from evomotion.core.checks import check_choice, check_fields, check_number, check_text
from evomotion.core.problem import Evaluation, GenomeSpec, Sense
from evomotion.errors import InputError
from evomotion.studies.grid_path.encoding import PerpendicularEncoding, parts_from_m
from evomotion.studies.grid_path.geometry import RULES, polyline_segments_valid
from evomotion.studies.grid_path.maps import GridMap, check_search_size, random_map, read_map
from evomotion.studies.grid_path.operators import PathOperators
from evomotion.studies.grid_path.tables import SegmentTables

BUNDLED = ("seed10a", "seed10b", "seed15", "seed20")


#: ``problem.n_parts`` (and the parts ``m`` gives) at most; ``retries``, ``repair_paths`` at
#: most; the side of a ``random:`` map at most
MAX_PARTS = 10_000
MAX_RETRIES = 100_000
MAX_REPAIR_PATHS = 10_000
MAX_RANDOM_MAP_SIZE = 4096
#: the documented ranges of the ``[problem]`` floats: the spacing factor ``m``, the penalty
#: per invalid segment (cells) and the repair corridor's half-width (cells)
MAX_M = 100.0
MAX_PENALTY = 1e9
MAX_REPAIR_RADIUS = 10_000.0


@dataclass(frozen=True)
class GridPathConfig:
    """The ``[problem]`` section of the grid-path study."""

    map: str = "seed10a"  # bundled name, a .map / 0-1 file, or "random:SIZE:DENSITY:SEED"
    start: str = ""  # "x,y" cell indices; default bottom-left cell
    goal: str = ""  # default top-right cell
    mode: str = "discrete"  # "discrete" (the paper's) or "continuous"
    m: float = 1.2  # paper's perpendicular spacing factor
    n_parts: int = 0  # > 0 overrides m
    rule: str = ""  # "" = closed for discrete, open for continuous
    penalty: float = 0.0  # per invalid segment; 0 = width + height
    retries: int = 20  # validity re-draws in initialisation and mutation
    repair: bool = False  # make the final best paths taut in their corridor (see repair.py)
    repair_radius: float = 2.0  # corridor half-width, cells
    repair_paths: int = 30  # how many of the best distinct final paths are repaired

    def validate(self) -> None:
        """One-line :class:`InputError` for impossible settings (the map file is read, and
        its own errors raised, when the problem is built)."""
        check_fields(self, "problem")
        check_text("problem.map", self.map, empty=False)
        if self.map.startswith("random:"):
            _check_random_spec(self.map)
        _cell(self.start, "start")
        _cell(self.goal, "goal")
        check_choice("problem.mode", self.mode, ("discrete", "continuous"))
        check_choice("problem.rule", self.rule, ("", *RULES))
        check_number("problem.m", self.m, lo=0.0, hi=MAX_M, lo_open=True)
        check_number("problem.n_parts", self.n_parts, lo=0, hi=MAX_PARTS, integer=True)
        check_number("problem.penalty", self.penalty, lo=0.0, hi=MAX_PENALTY)
        check_number("problem.retries", self.retries, lo=0, hi=MAX_RETRIES, integer=True)
        check_number("problem.repair_radius", self.repair_radius, lo=0.0,
                     hi=MAX_REPAIR_RADIUS, lo_open=True)
        check_number("problem.repair_paths", self.repair_paths, lo=0, hi=MAX_REPAIR_PATHS,
                     integer=True)


def _check_random_spec(spec: str) -> None:
    parts = spec.split(":")
    try:
        if len(parts) != 4:
            raise ValueError
        size, density, seed = int(parts[1]), float(parts[2]), int(parts[3])
    except ValueError:
        raise InputError(f"problem.map: expected 'random:SIZE:DENSITY:SEED', "
                         f"got {spec!r}") from None
    check_number("problem.map SIZE", size, lo=2, hi=MAX_RANDOM_MAP_SIZE, integer=True)
    check_number("problem.map DENSITY", density, lo=0.0, hi=1.0, hi_open=True)
    check_number("problem.map SEED", seed, lo=0, integer=True)


def _cell(text: str, what: str) -> tuple[int, int] | None:
    if not text:
        return None
    try:
        x, y = (int(v) for v in text.split(","))
    except ValueError:
        raise InputError(f"problem.{what} must be 'x,y' cell indices, got {text!r}") from None
    return x, y


def load_map(spec: str, start: tuple[int, int] | None = None,
             goal: tuple[int, int] | None = None) -> GridMap:
    """A bundled map by name, a file path, or ``random:SIZE:DENSITY:SEED``."""
    if spec.startswith("random:"):
        try:
            _, size, dens, seed = spec.split(":")
            m = random_map(int(size), float(dens), np.random.default_rng(int(seed)))
        except ValueError:
            raise InputError(f"expected 'random:SIZE:DENSITY:SEED', got {spec!r}") from None
        return GridMap(m.blocked, m.start, m.goal, spec).with_endpoints(start, goal)
    if spec in BUNDLED:
        ref = resources.files("evomotion.studies.grid_path") / "maps" / f"{spec}.map"
        with resources.as_file(ref) as p:
            return read_map(p, start, goal)
    if not Path(spec).exists():
        raise InputError(f"map {spec!r} is neither a file nor a bundled map "
                         f"({', '.join(BUNDLED)}) nor 'random:SIZE:DENSITY:SEED'")
    return read_map(spec, start, goal)


class GridPathProblem:
    """Batch evaluation of perpendicular-encoded paths on one map."""

    sense: Sense = "min"
    metric_names: tuple[str, ...] = ("length", "n_invalid")

    def __init__(self, cfg: GridPathConfig) -> None:
        self.cfg = cfg
        self.map = load_map(cfg.map, _cell(cfg.start, "start"), _cell(cfg.goal, "goal"))
        check_search_size(self.map)  # before the solvers' and tables' arrays are built
        if cfg.mode not in ("discrete", "continuous"):
            raise InputError(f"problem.mode must be 'discrete' or 'continuous', got {cfg.mode!r}")
        self.rule = cfg.rule or ("closed" if cfg.mode == "discrete" else "open")
        if self.rule not in RULES:
            raise InputError(f"problem.rule must be one of {', '.join(RULES)}, got {cfg.rule!r}")
        length = float(np.hypot(*(self.map.goal_xy - self.map.start_xy)))
        n = cfg.n_parts if cfg.n_parts > 0 else parts_from_m(length, cfg.m)
        if n > MAX_PARTS:
            raise InputError(f"problem.m: {cfg.m} divides this map's start-goal line into {n} "
                             f"parts, more than {MAX_PARTS}; expected a larger m")
        self.enc = PerpendicularEncoding.build(self.map, n, cfg.mode)
        self.penalty = cfg.penalty or float(self.map.width + self.map.height)
        self.genome: GenomeSpec = self.enc.genome()

    @cached_property
    def tables(self) -> SegmentTables | None:
        """Lookup tables of all segments (discrete mode on maps where they stay small)."""
        if self.cfg.mode != "discrete" or not SegmentTables.feasible(self.enc, self.map.blocked):
            return None
        return SegmentTables(self.enc, self.map.blocked, self.rule)

    @cached_property
    def operators(self) -> PathOperators:
        return PathOperators(self.enc, self.map.blocked, self.rule, retries=self.cfg.retries,
                             tables=self.tables)

    def decode(self, genomes: np.ndarray) -> np.ndarray:
        return self.enc.decode(genomes)

    def initial_population(self, n: int, rng: np.random.Generator) -> np.ndarray:
        """The paper's valid initial paths (the run loop passes them to the optimizer)."""
        return self.operators.initial_population(n, rng)

    def mutate(self, x: np.ndarray, rng: np.random.Generator, rate: float) -> np.ndarray:
        """The paper's validity-keeping path mutation, replacing the registry mutation."""
        return self.operators.mutate(x, rng, rate)

    def evaluate(self, genomes: np.ndarray) -> Evaluation:
        genomes = np.asarray(genomes, dtype=float).reshape(-1, self.genome.dim)
        looked_up = self.tables.chromosomes(genomes) if self.tables is not None else None
        if looked_up is not None:
            ok, seg = looked_up
        else:
            pts = self.enc.decode(genomes)
            seg = np.hypot(*np.moveaxis(np.diff(pts, axis=1), -1, 0))
            ok = polyline_segments_valid(self.map.blocked, pts, self.rule)
        length = np.add.reduce(seg, axis=1)  # ndarray.sum without its Python wrapper
        n_invalid = np.add.reduce(~ok, axis=1)
        return Evaluation(length + self.penalty * n_invalid,
                          {"length": length, "n_invalid": n_invalid.astype(float)})
