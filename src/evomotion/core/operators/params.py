"""Validation of operator parameters (``crossover_params``, ``mutation_params``, ...).

The valid keys of an operator are the keyword parameters of its registered function after the
fixed ones of its kind (crossover ``a, b, rng``; mutation ``x, lower, upper, rng, rate``;
selection ``cost, n, rng``), read with :func:`inspect.signature`, so a new operator needs no
entry here to get its keys checked. The values must be numbers (``int`` where the default is
an ``int``), finite, and inside :data:`RANGES` where the operator has a range; a parameter
whose default is ``None`` (``gene_rate``) also accepts ``None`` (``--set ...=none``).
"""

from __future__ import annotations

import inspect
from collections.abc import Callable
from typing import Any

from evomotion.core.checks import check_number
from evomotion.errors import InputError

#: the leading parameters every operator of a kind takes (not user-settable)
FIXED: dict[str, tuple[str, ...]] = {
    "crossover": ("a", "b", "rng"),
    "mutation": ("x", "lower", "upper", "rng", "rate"),
    "selection": ("cost", "n", "rng"),
}

#: ``(kind, operator, parameter) -> check_number keyword arguments`` (the operator's range)
RANGES: dict[tuple[str, str, str], dict[str, Any]] = {
    ("crossover", "uniform", "swap_prob"): {"lo": 0.0, "hi": 1.0},
    ("crossover", "blx_alpha", "alpha"): {"lo": 0.0},
    ("crossover", "sbx", "eta"): {"lo": 0.0},
    ("crossover", "beta_blend", "beta_max"): {"lo": 0.0},
    ("mutation", "uniform_reset", "gene_rate"): {"lo": 0.0, "hi": 1.0},
    ("mutation", "gaussian", "gene_rate"): {"lo": 0.0, "hi": 1.0},
    ("mutation", "gaussian", "sigma"): {"lo": 0.0, "lo_open": True},
    ("mutation", "perturb_k", "k"): {"lo": 1},
    ("mutation", "perturb_k", "delta"): {"lo": 0.0},
    ("selection", "tournament", "k"): {"lo": 1},
    ("selection", "rank", "pressure"): {"lo": 1.0, "hi": 2.0},
}


def operator_parameters(kind: str, fn: Callable[..., Any]) -> dict[str, inspect.Parameter]:
    """The user-settable parameters of operator ``fn`` of ``kind``, by name."""
    params = list(inspect.signature(fn).parameters.values())
    fixed = FIXED[kind]
    return {p.name: p for p in params[len(fixed):]
            if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)}


def check_operator_params(key: str, kind: str, name: str, fn: Callable[..., Any],
                          params: Any, *, limits: dict[str, dict[str, Any]] | None = None
                          ) -> None:
    """Raise a one-line :class:`InputError` unless ``params`` suit operator ``fn``.

    ``key`` is the config key (``algorithm.mutation_params``); ``limits`` adds bounds known
    only to the caller, by parameter (for example tournament ``k`` at most ``pop_size``)."""
    if not isinstance(params, dict):
        raise InputError(f"{key}: expected a table of parameters, got "
                         f"{type(params).__name__} {params!r}")
    valid = operator_parameters(kind, fn)
    for p, value in params.items():
        if p not in valid:
            names = ", ".join(valid) or "none"
            raise InputError(f"{key}: unknown parameter {p!r} for {kind} {name!r}; "
                             f"valid: {names}")
        default = valid[p].default
        if value is None:
            if default is None:
                continue
            raise InputError(f"{key}.{p}: expected a number, got none")
        rng = dict(RANGES.get((kind, name, p), {}))
        rng.update((limits or {}).get(p, {}))
        check_number(f"{key}.{p}", value, integer=isinstance(default, int)
                     and not isinstance(default, bool), **rng)


def check_genome_params(cfg: Any, genome: Any) -> None:
    """The checks that need the genome: ``perturb_k``'s ``k`` at most the genome's length."""
    if getattr(cfg, "mutation", None) == "perturb_k":
        k = cfg.mutation_params.get("k", 1)
        check_number("algorithm.mutation_params.k", k, lo=1, hi=genome.dim, integer=True)
