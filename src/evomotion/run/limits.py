"""Refuse a run whose population cannot fit in memory, before any array is allocated.

:func:`check_memory` estimates the bytes a run's population needs and compares them with
the memory available now (``MemAvailable`` of ``/proc/meminfo``, else ``sysconf``):

- the population arrays: ``pop_size x genome dim x 8 bytes x`` :data:`POPULATION_FACTOR`
  (population, offspring, mutation and clipping copies, evaluation temporaries);
- CMA-ES: also its ``dim x dim`` matrices (covariance, eigenvectors, update temporaries);
- the study's own working memory when its problem config has ``memory_bytes(pop_size) ->
  int`` (the MuJoCo studies: pop_size x horizon steps x state size of the recorded rollout).

The genome dim is the problem's (``problem.genome.dim``) when the problem is built, else the
config's ``genome_dim()`` when the problem config has one, else 1 (a lower bound, so the
check never refuses what might fit). :func:`evomotion.run.config.config_from_dict` calls it
without the problem; the run loop calls it again with the problem it built.
"""

from __future__ import annotations

from typing import Any

from evomotion.errors import InputError
from evomotion.run.contracts import (
    EstimatesDeviceMemory,
    EstimatesMemory,
    NamesMemoryKeys,
    SizedGenome,
)
from evomotion.sysmem import available_bytes

#: arrays of ``pop_size x dim`` doubles alive at once in a generation (a generous count)
POPULATION_FACTOR = 16
#: ``dim x dim`` double matrices alive at once in a CMA-ES update
COVARIANCE_FACTOR = 8


def format_bytes(n: float) -> str:
    """``7.5 TB``, ``20.1 GB``, ``512 B`` (decimal units)."""
    for unit in ("B", "kB", "MB", "GB", "TB", "PB", "EB"):
        if abs(n) < 1000 or unit == "EB":
            return f"{n:.0f} {unit}" if unit == "B" else f"{n:.1f} {unit}"
        n /= 1000
    return f"{n:.1f} EB"  # pragma: no cover


def genome_dim(config: Any, problem: Any = None) -> int | None:
    """The genome's length: the problem's, else the problem config's ``genome_dim()``."""
    if problem is not None and getattr(problem, "genome", None) is not None:
        return int(problem.genome.dim)
    return int(config.problem.genome_dim()) if isinstance(config.problem, SizedGenome) else None


def population_size(algorithm: Any, dim: int) -> int:
    """Individuals evaluated at once: ``algorithm.pop_size`` (CMA-ES ``0``: its default)."""
    pop = int(getattr(algorithm, "pop_size", 0) or 0)
    if pop == 0 and getattr(algorithm, "name", None) == "cmaes":
        from evomotion.core.cmaes_params import default_lambda

        pop = default_lambda(max(dim, 1))
    return pop


def _setting(config: Any, key: str) -> str:
    section, _, name = key.partition(".")
    return f"{key}={getattr(getattr(config, section), name)}"


def memory_terms(config: Any, problem: Any = None) -> list[tuple[int, str]]:
    """``(bytes, what)`` of each part of the estimate (see the module doc); ``what`` names
    the settings that size it, e.g. ``algorithm.pop_size=100 x 30 genes: the population``."""
    dim = genome_dim(config, problem)
    d = max(dim or 1, 1)
    alg = config.algorithm
    pop = population_size(alg, d)
    genes = f" x {d} genes" if dim is not None else ""
    terms = [(pop * d * 8 * POPULATION_FACTOR,
              f"algorithm.pop_size={getattr(alg, 'pop_size', pop)}{genes}: the population "
              "needs")]
    if getattr(alg, "name", None) == "cmaes":
        terms.append((d * d * 8 * COVARIANCE_FACTOR,
                      f"algorithm.name=cmaes with {d} genes: its covariance matrices need"))
    if isinstance(config.problem, EstimatesMemory) and pop:
        named = config.problem.memory_keys if isinstance(config.problem, NamesMemoryKeys) \
            else ()
        keys = ", ".join(_setting(config, f"problem.{k}") for k in named)
        terms.append((int(config.problem.memory_bytes(pop)), f"algorithm.pop_size={pop}"
                                    f"{', ' + keys if keys else ''}: the simulated "
                                    "trajectories need"))
    return terms


def check_memory(study: Any, config: Any, problem: Any = None) -> None:
    """Raise a one-line :class:`InputError` when the run's population needs more memory than
    is available, e.g. ``algorithm.pop_size=1000000000 x 30 genes: the population needs about
    3.8 TB, more than the 20.1 GB available`` (it names the largest part of the estimate).

    ``study`` is the :class:`~evomotion.studies.base.Study` (unused today, kept for
    study-level limits), ``config`` the resolved :class:`~evomotion.run.config.Config`,
    ``problem`` the built problem or ``None`` (then the config's ``genome_dim()``, else 1
    gene). A problem config may name the fields its ``memory_bytes`` depends on in a class
    attribute ``memory_keys`` (a tuple of field names) for the message."""
    check_device_memory(config, problem)
    terms = memory_terms(config, problem)
    total = sum(b for b, _ in terms)
    avail = available_bytes()
    if avail is None or total <= avail:
        return
    _, what = max(terms)
    raise InputError(f"{what} about {format_bytes(total)}, more than the "
                     f"{format_bytes(avail)} available")


def check_device_memory(config: Any, problem: Any) -> None:
    """Raise a one-line :class:`InputError` when a GPU-backend problem's batch (its
    ``device_memory(pop_size) -> (needed, free, device) | None``) cannot fit on its device."""
    if not isinstance(problem, EstimatesDeviceMemory):
        return
    pop = population_size(config.algorithm, max(genome_dim(config, problem) or 1, 1))
    found = problem.device_memory(pop) if pop else None
    if found is None:
        return
    needed, free, device = found
    if free is None or needed <= free:
        return
    raise InputError(f"algorithm.pop_size={pop}, problem.backend="
                     f"{getattr(config.problem, 'backend', '?')}: one batch needs about "
                     f"{format_bytes(needed)} on {device}, more than the {format_bytes(free)} "
                     "free")
