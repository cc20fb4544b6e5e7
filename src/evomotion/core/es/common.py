"""What the four evolution strategies share: the centre, the box, mirrored pairs, the noise.

The centre (distribution mean) starts at the middle of the genome bounds (``0`` on a gene
whose bounds are infinite on both sides, the finite bound on a half-infinite one), or at row
0 of the ``population`` given to ``init`` (clipped into the bounds; the other rows are not
used: a distribution has one mean). Asked genomes are clipped into the bounds and the centre
is kept inside them after each update (a projected step): policy parameters are effectively
unbounded, so a problem should give bounds wide enough not to matter. None of these methods
has a mutation operator: a ``mutate`` hook raises ``ValueError``.

Every ``tell`` estimates from the genomes it is told (not from noise kept since ``ask``), so
what enters an update is what was evaluated. For the mirrored methods, rows ``k`` and
``k + N`` of a population of ``2N`` are the pair ``centre ± perturbation``; a clipped pair is
mirrored only inside the bounds and enters as its half-difference.

Shared noise table (``noise_table = M > 0``; Salimans et al. 2017, section 2.1, and Mania et
al. 2018's code): the perturbations are windows of one table of ``M`` standard normal numbers
drawn once from the fixed seed :data:`NOISE_TABLE_SEED`, ``ε_k = table[o_k : o_k + d]`` with
the offsets ``o_k`` drawn from the passed generator at every ``ask``. An ``ask`` then copies
``N d`` numbers instead of drawing them (drawing is most of an ``ask``'s time at large ``d``);
windows overlap, as in the papers. The table is a pure function of ``M``, so a resumed run,
another process or another machine rebuilds the same one; it is kept per process, one per size
(``M`` float64: 8 bytes each). ``0`` (the default) draws fresh numbers at every ``ask``.
"""

from __future__ import annotations

from functools import lru_cache
from typing import Any

import numpy as np

from evomotion.core.checks import MAX_POP_SIZE, check_fields, check_number
from evomotion.core.optimizer import MutateFn, Optimizer
from evomotion.core.problem import GenomeSpec
from evomotion.errors import InputError


def check_pop_size(cfg: Any, *, even: bool, allow_zero: bool = False) -> None:
    """Generic field checks plus ``pop_size`` (even for mirrored sampling)."""
    check_fields(cfg, "algorithm")
    check_number("algorithm.pop_size", cfg.pop_size, hi=MAX_POP_SIZE, integer=True,
                 lo=0 if allow_zero else 2)
    if cfg.pop_size != 0 and cfg.pop_size < 2:
        raise ValueError(f"algorithm.pop_size must be >= 2, got {cfg.pop_size}")
    if even and cfg.pop_size % 2:
        raise ValueError(f"algorithm.pop_size must be even (mirrored pairs), got {cfg.pop_size}")


#: the seed of every shared noise table (a constant: the table depends on its size only)
NOISE_TABLE_SEED = 20170310
#: the largest table accepted (2**27 numbers = 1 GiB)
MAX_NOISE_TABLE = 2**27


def check_noise_table(cfg: Any, dim: int | None = None) -> None:
    """``cfg.noise_table``: 0 (fresh noise) or a table size; with ``dim``, at least ``dim``."""
    check_number("algorithm.noise_table", cfg.noise_table, lo=0, hi=MAX_NOISE_TABLE,
                 integer=True)
    if dim is not None and 0 < cfg.noise_table < dim:
        raise InputError(f"algorithm.noise_table must be 0 or at least the genome's {dim} "
                         f"genes, got {cfg.noise_table}")


@lru_cache(maxsize=2)
def noise_table(size: int) -> np.ndarray:
    """The shared table of ``size`` standard normal numbers (read-only)."""
    table = np.random.default_rng(NOISE_TABLE_SEED).standard_normal(int(size))
    table.setflags(write=False)
    return table


def check_positive(cfg: Any, *keys: str) -> None:
    for key in keys:
        check_number(f"algorithm.{key}", getattr(cfg, key), lo=0.0, lo_open=True)


def check_nonneg(cfg: Any, *keys: str) -> None:
    for key in keys:
        check_number(f"algorithm.{key}", getattr(cfg, key), lo=0.0)


def check_unit(cfg: Any, *keys: str, closed: bool = False) -> None:
    """Each ``cfg.<key>`` in ``[0, 1)`` (``closed``: ``[0, 1]``)."""
    for key in keys:
        check_number(f"algorithm.{key}", getattr(cfg, key), lo=0.0, hi=1.0, hi_open=not closed)


class GaussianES(Optimizer):
    """Base of the evolution strategies: a Gaussian search distribution around a centre."""

    def __init__(self, genome: GenomeSpec, cfg: Any, *, mutate: MutateFn | None = None) -> None:
        if mutate is not None:
            raise ValueError(f"{self.name}: an evolution strategy has no mutation operator to "
                             "replace; a mutate hook is not supported")
        super().__init__(genome)
        cfg.validate()
        if hasattr(cfg, "noise_table"):
            check_noise_table(cfg, genome.dim)
        self.cfg = cfg
        self.lower, self.upper = genome.lower, genome.upper
        self.bounded = bool(np.isfinite(self.lower).any() or np.isfinite(self.upper).any())

    def center(self, state: Any) -> np.ndarray:
        """The distribution mean: the point a policy search deploys and evaluates."""
        return np.array(state.center, dtype=float)

    def start_center(self, population: np.ndarray | None) -> np.ndarray:
        """The middle of the bounds, or row 0 of ``population`` (clipped into the bounds)."""
        lo, hi = self.lower, self.upper
        if population is not None:
            x = np.asarray(population, dtype=float)
            if x.ndim != 2 or x.shape[0] < 1 or x.shape[1] != self.genome.dim \
                    or not np.isfinite(x[0]).all():
                raise ValueError(f"{self.name}: initial population has shape {x.shape} (or a "
                                 f"non-finite row 0), want (k, {self.genome.dim})")
            return self.clip(x[0].copy())
        finite_lo, finite_hi = np.isfinite(lo), np.isfinite(hi)
        mid = np.where(finite_lo & finite_hi, 0.5 * (np.where(finite_lo, lo, 0.0)
                                                      + np.where(finite_hi, hi, 0.0)), 0.0)
        return np.clip(mid, lo, hi)

    def clip(self, x: np.ndarray) -> np.ndarray:
        """``x`` clipped into the bounds, in place (``x`` must be a fresh array)."""
        if self.bounded:
            np.maximum(x, self.lower, out=x)
            np.minimum(x, self.upper, out=x)
        return x

    def check_told(self, genomes: np.ndarray) -> None:
        n = self.expected_population()
        if genomes.shape[0] != n:
            raise ValueError(f"{self.name}: tell got {genomes.shape[0]} genomes, the population "
                             f"is {n}")

    def mirrored(self, rng: np.random.Generator, center: np.ndarray, scale: Any,
                 n: int) -> np.ndarray:
        """``[center + p; center - p]`` with ``p = scale * N(0, I)[n, d]`` drawn in one call,
        or taken from the shared noise table (``cfg.noise_table``; see the module), rows ``k``
        and ``k + n`` a pair, clipped; built in one fresh array."""
        x = np.empty((2 * n, self.genome.dim))
        p = self.scaled_normal(rng, scale, out=x[:n])
        inside = not self.bounded or self._inside(center, p)
        np.subtract(center, p, out=x[n:])
        p += center
        return x if inside else self.clip(x)

    def scaled_normal(self, rng: np.random.Generator, scale: Any, out: np.ndarray) -> np.ndarray:
        """``out[n, d] = scale * N(0, I)``: drawn in one call, or windows of the shared noise
        table (``cfg.noise_table``; see the module) at offsets drawn from ``rng``."""
        d = self.genome.dim
        size = int(getattr(self.cfg, "noise_table", 0))
        if size:
            offsets = rng.integers(0, size - d + 1, size=out.shape[0])
            windows = np.lib.stride_tricks.sliding_window_view(noise_table(size), d)
            np.multiply(windows[offsets], scale, out=out)
        else:
            rng.standard_normal(out=out)
            out *= scale
        return out

    def _inside(self, center: np.ndarray, p: np.ndarray) -> bool:
        """Whether every ``center ± p`` row is inside the bounds already (then clipping, two
        passes over the population, changes nothing and is skipped): one pass over ``p``."""
        reach = max(float(p.max()), -float(p.min()))  # rounding is monotone: c - p >= c - reach
        return bool(np.all(center - reach >= self.lower) and np.all(center + reach <= self.upper))


def half_differences(genomes: np.ndarray) -> np.ndarray:
    """``(x_k - x_{k+N}) / 2`` of the mirrored pairs: the perturbations as evaluated."""
    n = genomes.shape[0] // 2
    d: np.ndarray = genomes[:n] - genomes[n:]
    d *= 0.5
    return d
