"""Mirror-symmetric policies: the parameters of a policy that acts as its own mirror image.

A robot symmetric about its sagittal plane has a mirror function on states and actions; a
policy ``π`` is mirror-symmetric when ``π(M_o s) = M_a π(s)`` (Yu, Turk and Liu 2018,
"Learning Symmetric and Low-Energy Locomotion", ACM Transactions on Graphics 37(4), section 4,
where it is a loss term; here it is a constraint on the parameters). Both mirrors are signed
permutations ``y' = sign * y[perm]`` that undo themselves (:class:`SignedPermutation`).

For the structured policy (:mod:`.structured`: tape ``C``, gains ``K``, command feedback
``G``), a gait's mirror image is the same gait half a cycle later (``φ -> φ + π``: the
harmonic ``k`` of the tape changes sign with ``(-1)^k``) with the command mirrored
(``M_c``, e.g. ``(vx, vy, ω) -> (vx, -vy, -ω)``), so symmetry reads

    C = M_a C D,    K = M_a K M_x,    G = M_c G M_x                       (1)

(``D``: the sign of each tape feature under the half cycle and the mirrored command; ``M_x``:
the observation's mirror on the feedback inputs). Each is one signed permutation ``T`` of the
flat parameters with ``T² = I`` (:func:`structured_mirror`); its fixed points ``p = T p`` are
``p = B z`` (:class:`MirrorBasis`): a parameter that is its own image with sign +1 is one free
number, with sign −1 it is 0, and a pair ``p_j = s p_i`` is one free number. The search runs
on ``z``: about half as many numbers, every policy symmetric.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from evomotion.core.policies.structured import StructuredSpec


@dataclass(frozen=True, eq=False)
class SignedPermutation:
    """``y' = sign * y[..., perm]``, an involution (applying it twice gives ``y``)."""

    perm: np.ndarray
    sign: np.ndarray

    def __post_init__(self) -> None:
        perm = np.asarray(self.perm, dtype=np.int64)
        sign = np.asarray(self.sign, dtype=np.float64)
        n = perm.size
        if perm.shape != (n,) or sign.shape != (n,) or \
                not np.array_equal(np.sort(perm), np.arange(n)):
            raise ValueError("a signed permutation needs a permutation of 0..n-1 and n signs")
        if not np.isin(sign, (-1.0, 1.0)).all():
            raise ValueError("signs must be +1 or -1")
        if not (np.array_equal(perm[perm], np.arange(n)) and (sign * sign[perm] == 1).all()):
            raise ValueError("a mirror must undo itself (perm[perm] = i, sign[i] sign[perm[i]] "
                             "= 1)")
        object.__setattr__(self, "perm", perm)
        object.__setattr__(self, "sign", sign)

    def apply(self, y: np.ndarray) -> np.ndarray:
        return self.sign * np.asarray(y, dtype=np.float64)[..., self.perm]


@dataclass(frozen=True, eq=False)
class MirrorBasis:
    """The fixed points ``p = T p`` of a :class:`SignedPermutation` ``T`` as ``p = expand(z)``.

    ``index[i]``: the free number parameter ``i`` reads (−1: it is 0), ``sign[i]`` its sign."""

    index: np.ndarray
    sign: np.ndarray
    dim: int

    @classmethod
    def of(cls, t: SignedPermutation) -> MirrorBasis:
        i = np.arange(t.perm.size)
        free = (i < t.perm) | ((i == t.perm) & (t.sign > 0))  # one per orbit that may be != 0
        number = np.cumsum(free) - 1
        rep = np.minimum(i, t.perm)  # each orbit's first parameter
        index = np.where((i == t.perm) & (t.sign < 0), -1, number[rep])
        # the first of a pair reads +z, its partner p_j = sign_j p_i
        sign = np.where(index < 0, 0.0, np.where(i == rep, 1.0, t.sign))
        return cls(index.astype(np.int64), sign, int(free.sum()))

    def expand(self, z: np.ndarray) -> np.ndarray:
        """``p[..., n]`` of ``z[..., dim]``."""
        z = np.asarray(z, dtype=np.float64)
        if self.dim == 0:  # every parameter forced to 0
            return np.zeros(z.shape[:-1] + self.index.shape)
        return self.sign * z[..., np.maximum(self.index, 0)]

    def reduce(self, p: np.ndarray) -> np.ndarray:
        """``z`` of the symmetric parameters nearest ``p[n]`` (the mean over each orbit)."""
        p = np.asarray(p, dtype=np.float64)
        keep = self.index >= 0
        sums = np.bincount(self.index[keep], (self.sign * p)[keep], minlength=self.dim)
        return sums / np.bincount(self.index[keep], minlength=self.dim)


def _parity(harmonics: int) -> np.ndarray:
    """The sign of ``(1, sin φ, cos φ, ..., sin Hφ, cos Hφ)`` under ``φ -> φ + π``."""
    k = np.concatenate([[0], np.repeat(np.arange(1, harmonics + 1), 2)])
    return np.where(k % 2 == 0, 1.0, -1.0)


def structured_mirror(spec: StructuredSpec, action: SignedPermutation,
                      observation: SignedPermutation) -> SignedPermutation:
    """The flat parameters' mirror ``T`` of equation (1) for ``spec`` (a structured policy
    with a command), the action mirror ``M_a`` and the observation mirror (every column; the
    phase columns map to themselves, the command columns to themselves with their signs)."""
    o, a = spec.obs_dim, spec.act_dim
    if action.perm.size != a or observation.perm.size != o:
        raise ValueError(f"mirrors of {action.perm.size} actions and {observation.perm.size} "
                         f"observations, expected {a} and {o}")
    cmd = np.asarray(spec.command_columns, dtype=np.int64)
    fixed = np.concatenate([cmd, np.asarray(spec.phase_columns)])
    if cmd.size == 0 or not np.array_equal(observation.perm[fixed], fixed) or \
            not (observation.sign[np.asarray(spec.phase_columns)] > 0).all():
        raise ValueError("the structured mirror needs a command, and the phase and command "
                         "columns mirrored onto themselves (the phase with sign +1)")
    fb = spec.feedback_columns
    where = np.full(o, -1)
    where[fb] = np.arange(fb.size)
    x_perm, x_sign = where[observation.perm[fb]], observation.sign[fb]
    s_cmd = observation.sign[cmd]
    feat_sign = np.concatenate([_parity(spec.harmonics)] +
                               [s * _parity(spec.harmonics) for s in s_cmd])
    idx = [np.asarray(w).astype(np.int64)  # each layer's flat parameter numbers
           for w, _ in spec.unflatten(np.arange(spec.n_params, dtype=np.float64))]
    perm = np.empty(spec.n_params, dtype=np.int64)
    sign = np.empty(spec.n_params)
    C, K = idx[0], idx[1]
    perm[C] = C[action.perm]
    sign[C] = action.sign[:, None] * feat_sign[None]
    perm[K] = K[action.perm][:, x_perm]
    sign[K] = action.sign[:, None] * x_sign[None]
    if len(idx) > 2:
        G = idx[2]
        perm[G] = G[:, x_perm]
        sign[G] = s_cmd[:, None] * x_sign[None]
    return SignedPermutation(perm, sign)


def with_mirror_image(count: np.ndarray, mean: np.ndarray, m2: np.ndarray,
                      observation: SignedPermutation
                      ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Each episode's observation moments (``count[n]``, ``mean[n, o]``, ``m2[n, o]``) merged
    with those of its mirror image (Chan et al. 1979's pairwise update): an ARS V2 normaliser
    fed with them is exactly symmetric, so a symmetric policy stays symmetric once it
    normalises its input."""
    count = np.asarray(count, dtype=np.float64)
    mirrored = observation.apply(mean)
    delta = mirrored - mean
    return (2.0 * count, 0.5 * (mean + mirrored),
            m2 + m2[..., observation.perm] + 0.5 * count[:, None] * delta * delta)
