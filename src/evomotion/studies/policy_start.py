"""A policy search that starts from an exported policy (``problem.start_policy``): fine-tuning
a controller under new settings, or a curriculum (a walk learnt on forward commands, then on
every direction).

The start is a ``policy.npz`` (:mod:`evomotion.core.policies.export`), or a run folder holding
one, of the same controller: the same kind, sizes, joints, ranges and structure as the run's
own policy (every array of the file but the parameters and the normaliser is compared with the
run's, and the first that differs is named). The search's centre starts at the file's
parameters (a mirror-symmetric controller's free numbers, :mod:`evomotion.core.policies.mirror`,
when the run is symmetric: the file must then be symmetric too). With ``problem.normalize``
the observation normaliser (ARS V2's running statistics) starts at the file's mean and standard
deviation, weighted as :data:`START_OBS_COUNT` states seen (about a million), so the file's
policy acts at first exactly as exported and the new run's own observations take over
gradually (a 32-row population on two 8 s episodes each sees about 26,000 states a generation,
twice that where a symmetric controller's normaliser also takes their mirror images, so they
weigh as much as the file's after 20-40 generations). Without normalisation the file must carry
the identity normaliser (mean 0, std 1).

The file is read when a new run is checked, before its folder is made
(:meth:`~evomotion.run.driver.Driver.check_new_run`), in the process that drives the search
(never by an evaluator's workers). A resume does not read it: the run's checkpoints hold
everything, so a resumed run continues bit for bit even if the file has moved.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.policies import normalizer
from evomotion.core.policies.normalizer import RunningStats
from evomotion.errors import InputError

#: the weight, in states seen, of a start policy's normaliser (see the module): about a
#: million; 2^20 + 1 so that ``std² (n − 1) / (n − 1)`` gives the file's std back exactly
START_OBS_COUNT = 2**20 + 1
_KEY = "problem.start_policy"


@dataclass(frozen=True, eq=False)
class StartPoint:
    """Where a search starts: its numbers ``genome[d]`` and the normaliser ``obs``."""

    genome: np.ndarray
    obs: RunningStats


def policy_file(path: str | Path) -> Path:
    """``path`` itself, or the ``policy.npz`` of the run folder ``path``; one line if none."""
    try:
        given = Path(path).expanduser()
        p = given / "policy.npz" if given.is_dir() else given
        found = p.is_file()
    except (RuntimeError, OSError, ValueError) as e:  # ~nobody, a name too long, NUL
        raise InputError(f"{_KEY}: expected a readable path, got {str(path)[:200]!r} "
                         f"({type(e).__name__})") from None
    if not found:
        why = "no policy.npz in it" if p is not given else "no such file"
        raise InputError(f"{_KEY}: expected a policy.npz or a run folder holding one, got "
                         f"{str(path)[:200]!r} ({why})")
    return p


def start_point(problem: Any, path: str) -> StartPoint | None:
    """The start of ``problem``'s search from the exported policy at ``path`` (``""``: none,
    the problem's own start). ``problem`` has ``policy`` (its spec), ``genome``, ``normalize``
    and optionally ``mirror`` (a symmetric controller's basis). Anything that does not fit is
    one :class:`~evomotion.errors.InputError` line naming the file and what was expected."""
    from evomotion.core.policies.export import read_policy_npz

    if not path:
        return None
    f = policy_file(path)
    got = read_policy_npz(f)  # a malformed file: one FileFormatError line
    check_same_controller(f, got.spec, problem.policy)
    x = np.asarray(got.params, dtype=np.float64)
    mirror = getattr(problem, "mirror", None)
    genome = x if mirror is None else mirror.basis.reduce(x)
    if mirror is not None and not np.allclose(mirror.basis.expand(genome), x, rtol=0.0,
                                              atol=1e-9 * (1.0 + float(np.abs(x).max()))):
        raise InputError(f"{_KEY}: {f} is not a mirror-symmetric controller; start a "
                         "symmetric run (problem.symmetric=true) from a symmetric one")
    lo, hi = problem.genome.lower, problem.genome.upper
    if genome.shape != lo.shape or ((genome < lo) | (genome > hi)).any():
        raise InputError(f"{_KEY}: {f}'s parameters lie outside this run's box "
                         f"[{float(lo.min()):g}, {float(hi.max()):g}] (problem.param_bound)")
    mean, std = got.obs_mean, got.obs_std
    if not problem.normalize:
        if (mean != 0).any() or (std != 1).any():
            raise InputError(f"{_KEY}: {f} was evaluated with an observation normaliser; "
                             "expected problem.normalize=true to start from it")
        obs = normalizer.init(mean.size)
    else:
        n = START_OBS_COUNT
        obs = RunningStats(np.array(n, dtype=np.int64), mean.copy(), std ** 2 * (n - 1))
    return StartPoint(genome.copy(), obs)


def check_same_controller(f: Path, spec: Any, own: Any, key: str = _KEY) -> None:
    """One line, headed ``key``, naming the first array in which the file's controller
    differs from the run's (its kind, sizes, structure, action scale, offset and range)."""
    from evomotion.core.policies.export import policy_arrays

    if type(spec) is not type(own):
        raise InputError(f"{key}: {f} is a {spec.kind} policy, this run's is {own.kind}")
    if (spec.obs_dim, spec.act_dim, spec.n_params) != (own.obs_dim, own.act_dim, own.n_params):
        raise InputError(f"{key}: {f} maps {spec.obs_dim} observations to {spec.act_dim} "
                         f"actions with {spec.n_params} parameters; this run's controller "
                         f"{own.obs_dim} to {own.act_dim} with {own.n_params} (expected the "
                         "same robot, joints and policy settings)")
    ident = (np.zeros(own.obs_dim), np.ones(own.obs_dim))
    theirs = policy_arrays(spec, np.zeros(spec.n_params), *ident)
    ours = policy_arrays(own, np.zeros(own.n_params), *ident)
    for name in sorted(set(theirs) | set(ours)):
        a, b = theirs.get(name), ours.get(name)
        same = a is not None and b is not None and a.shape == b.shape and (
            np.array_equal(a, b) if a.dtype.kind in "USbiu" else
            np.allclose(a, b, rtol=0.0, atol=1e-9, equal_nan=True))
        if not same:
            raise InputError(f"{key}: {f}'s {name!r} differs from this run's controller "
                             "(expected the same robot, joints and policy settings)")
