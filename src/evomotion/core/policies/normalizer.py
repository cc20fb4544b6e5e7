"""Observation normalisation with running statistics, as in ARS V2.

Mania, Guy & Recht 2018, "Simple random search provides a competitive approach to reinforcement
learning" (arXiv 1803.07055), Algorithm 2, V2: the policy acts on
``diag(Σ)^(-1/2) (s − μ)`` (line 5), where ``μ`` and ``Σ`` are the mean and the diagonal of the
covariance of all states seen since the start of training (line 8).

The statistics are an explicit, immutable :class:`RunningStats` (count, mean, M2 = the sum of
squared deviations from the mean) of flat numpy arrays, checkpointed like any optimizer state.
Batches are merged with the pairwise formula of Chan, Golub & LeVeque (1979, "Updating formulae
and a pairwise algorithm for computing sample variances", Stanford STAN-CS-79-773, eq. 2.1,
written here in means instead of sums)::

    n = n_A + n_B,   δ = μ_B − μ_A,   μ = μ_A + δ n_B / n,   M2 = M2_A + M2_B + δ² n_A n_B / n

and its k-way form (:func:`combine`: ``μ = Σ n_k μ_k / n``, ``M2 = Σ M2_k + Σ n_k (μ_k − μ)²``),
so that moments gathered by several workers, one row (individual) each, combine in row order to
the same bits however the rows were split among the workers.

Standard deviation (:func:`mean_std`): the sample variance ``M2 / (n − 1)`` as in the ARS code;
a coordinate whose std is below ``std_floor`` (default 1e-8), or any coordinate before two
states were seen, gets std 1 (it passes through centred, unscaled). ARS's public code instead
sets such a std to +inf (the coordinate is zeroed); a std of 1 keeps exported files finite and
lets a coordinate that starts to move later act at once.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: the default floor on the standard deviation (see the module)
STD_FLOOR = 1e-8


@dataclass(frozen=True, eq=False)
class RunningStats:
    """Running moments of every state seen: ``count`` (0-d int64), ``mean[o]``, ``m2[o]``."""

    count: np.ndarray
    mean: np.ndarray
    m2: np.ndarray

    @property
    def obs_dim(self) -> int:
        return int(self.mean.shape[0])


Moments = tuple[np.ndarray, np.ndarray, np.ndarray]  # (count, mean[o], M2[o]) of one batch


def init(obs_dim: int) -> RunningStats:
    """No state seen yet."""
    if int(obs_dim) < 1:
        raise ValueError(f"obs_dim must be at least 1, got {obs_dim}")
    return RunningStats(np.array(0, dtype=np.int64), np.zeros(int(obs_dim)),
                        np.zeros(int(obs_dim)))


def moments(obs: np.ndarray, valid: np.ndarray | None = None) -> Moments:
    """(count, mean, M2) of the states ``obs[..., o]`` (every leading index one state), only
    where ``valid[...]`` is true if given (steps after an early stop are left out)."""
    x = np.asarray(obs, dtype=np.float64)
    x = x.reshape(-1, x.shape[-1])
    if valid is None:
        n = x.shape[0]
        if n == 0:
            return np.array(0, dtype=np.int64), np.zeros(x.shape[1]), np.zeros(x.shape[1])
        mean = x.mean(axis=0)
        return np.array(n, dtype=np.int64), mean, ((x - mean) ** 2).sum(axis=0)
    keep = np.asarray(valid, dtype=bool).reshape(-1)
    if keep.shape[0] != x.shape[0]:
        raise ValueError(f"valid has {keep.shape[0]} entries for {x.shape[0]} states")
    return moments(x[keep])


def moments_per_row(obs: np.ndarray, valid: np.ndarray | None = None) -> Moments:
    """The moments of each row ``obs[k, ..., o]`` (one individual's states) at once:
    ``counts[k]``, ``means[k, o]``, ``m2s[k, o]``; ``valid[k, ...]`` as in :func:`moments`."""
    x = np.asarray(obs, dtype=np.float64)
    k, o = x.shape[0], x.shape[-1]
    x = x.reshape(k, int(np.prod(x.shape[1:-1])), o)
    w = np.ones(x.shape[:2], dtype=bool) if valid is None else np.asarray(valid, dtype=bool)
    if w.size != x.shape[0] * x.shape[1] or w.shape[:1] != (k,):
        raise ValueError(f"valid has shape {w.shape} for states of shape {x.shape[:2]}")
    w = w.reshape(x.shape[:2])
    counts = w.sum(axis=1).astype(np.int64)
    xw = np.where(w[..., None], x, 0.0)  # invalid steps may hold NaN: never touched
    means = xw.sum(axis=1) / np.maximum(counts, 1)[:, None]
    m2s = (np.where(w[..., None], x - means[:, None, :], 0.0) ** 2).sum(axis=1)
    return counts, means, m2s


def combine(counts: np.ndarray, means: np.ndarray, m2s: np.ndarray) -> Moments:
    """The moments of k batches taken together, in row order (Chan et al.'s k-way form)."""
    c = np.asarray(counts, dtype=np.int64)
    n = int(c.sum())
    if n == 0:
        return np.array(0, dtype=np.int64), np.zeros(means.shape[1]), np.zeros(means.shape[1])
    w = c.astype(np.float64)[:, None]
    mean = (w * means).sum(axis=0) / n
    m2 = m2s.sum(axis=0) + (w * (means - mean) ** 2).sum(axis=0)
    return np.array(n, dtype=np.int64), mean, m2


def merge(stats: RunningStats, batch: Moments) -> RunningStats:
    """``stats`` with one more batch's moments (Chan et al. eq. 2.1, see the module)."""
    n_b, mean_b, m2_b = np.asarray(batch[0], dtype=np.int64), batch[1], batch[2]
    if np.shape(mean_b) != stats.mean.shape or np.shape(m2_b) != stats.m2.shape:
        raise ValueError(f"batch moments of shape {np.shape(mean_b)} for statistics of "
                         f"{stats.obs_dim} observations")
    n_a = int(stats.count)
    nb = int(n_b)
    if nb < 0:
        raise ValueError(f"a batch of {nb} states")
    if nb == 0:
        return stats
    n = n_a + nb
    delta = np.asarray(mean_b, dtype=np.float64) - stats.mean
    mean = stats.mean + delta * (nb / n)
    m2 = stats.m2 + np.asarray(m2_b, dtype=np.float64) + delta ** 2 * (n_a * nb / n)
    return RunningStats(np.array(n, dtype=np.int64), mean, m2)


def update(stats: RunningStats, obs: np.ndarray, valid: np.ndarray | None = None
           ) -> RunningStats:
    """``stats`` after the states of a population's rollouts ``obs[k, ..., o]``: per-row
    moments combined in row order, then merged (the same bits however rows were split)."""
    return merge(stats, combine(*moments_per_row(obs, valid)))


def mean_std(stats: RunningStats, std_floor: float = STD_FLOOR
             ) -> tuple[np.ndarray, np.ndarray]:
    """``(μ[o], std[o])`` to normalise with: sample std, below ``std_floor`` -> 1 (module)."""
    n = int(stats.count)
    var = stats.m2 / max(n - 1, 1)
    std = np.sqrt(np.maximum(var, 0.0))
    std = np.where((std < std_floor) | (n < 2), 1.0, std)
    return stats.mean.copy(), std
