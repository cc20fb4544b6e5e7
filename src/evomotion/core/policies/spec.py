"""What linear and MLP policies share: the action map, the flat parameter layout, the batched
forward pass (the structured policy, :mod:`.structured`, keeps the first two and has its own).

A policy is a small frozen spec; its parameters are one flat float64 vector ``params[P]`` (what
the optimizers see), laid out layer by layer as ``W[out, in]`` (row-major) then, where the layer
has one, ``b[out]``. The forward pass of a whole population at once
(:meth:`PolicySpec.act`: each row its own parameters and its own observation)::

    x = clip((obs − μ) / std, −clip_obs, clip_obs)          # ARS V2 normalisation
    h = tanh(W_i h + b_i)                                     # hidden layers (MLP)
    y = W_L h + b_L
    action = clip(offset + scale * y, low, high)              # linear (ARS: no squashing)
    action = clip(offset + scale * tanh(y), low, high)        # MLP

``clip_obs`` defaults to +inf (no clipping), as in ARS's public code, which divides by the std
and does not clip; a finite value (10, as many RL libraries use) bounds the inputs when a sensor
that was constant so far starts to move.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

Layer = tuple[np.ndarray, np.ndarray | None]  # (W[..., out, in], b[..., out] or None)


def _vector(value, n: int, name: str) -> np.ndarray:
    a = np.array(value, dtype=np.float64)
    if a.ndim == 0:
        a = np.full(n, float(a))
    if a.shape != (n,):
        raise ValueError(f"{name} has shape {a.shape}, expected a number or ({n},)")
    if np.isnan(a).any():
        raise ValueError(f"{name} holds NaN")
    a.setflags(write=False)
    return a


@dataclass(frozen=True, eq=False)
class PolicySpec:
    """Sizes and the action map: ``action = clip(offset + scale * output, low, high)``.

    ``scale``, ``offset``, ``low``, ``high`` are numbers or ``(act_dim,)`` arrays (e.g. the
    nominal pose as ``offset`` and the joint ranges as ``low``/``high``); ``clip_obs`` bounds
    the normalised observation (+inf: no clipping).
    """

    obs_dim: int
    act_dim: int
    scale: np.ndarray | float = 1.0
    offset: np.ndarray | float = 0.0
    low: np.ndarray | float = -math.inf
    high: np.ndarray | float = math.inf
    clip_obs: float = math.inf

    kind: ClassVar[str] = ""
    squash_output: ClassVar[bool] = False  # tanh on the last layer's output

    def __post_init__(self) -> None:
        for name in ("obs_dim", "act_dim"):
            v = getattr(self, name)
            if isinstance(v, bool) or not isinstance(v, int | np.integer) or v < 1:
                raise ValueError(f"{name} must be a whole number >= 1, got {v!r}")
            object.__setattr__(self, name, int(v))
        for name in ("scale", "offset", "low", "high"):
            object.__setattr__(self, name, _vector(getattr(self, name), self.act_dim, name))
        if not np.isfinite(self.scale).all() or not np.isfinite(self.offset).all():
            raise ValueError("scale and offset must be finite")
        if (np.asarray(self.low) > np.asarray(self.high)).any():
            raise ValueError("low must not exceed high")
        c = float(self.clip_obs)
        if not c > 0:
            raise ValueError(f"clip_obs must be > 0 (inf: no clipping), got {self.clip_obs!r}")
        object.__setattr__(self, "clip_obs", c)

    # -- what a kind defines -------------------------------------------------------------
    def layer_shapes(self) -> list[tuple[int, int]]:
        """``(out, in)`` of every layer, input to output."""
        raise NotImplementedError

    def layer_has_bias(self, i: int) -> bool:
        return True

    # -- shared ----------------------------------------------------------------------------
    @property
    def n_params(self) -> int:
        """P, the length of the flat parameter vector."""
        return sum(o * i + (o if self.layer_has_bias(k) else 0)
                   for k, (o, i) in enumerate(self.layer_shapes()))

    def unflatten(self, params: np.ndarray) -> list[Layer]:
        """The layers ``(W[..., out, in], b[..., out] or None)`` of ``params[..., P]`` (views)."""
        p = np.asarray(params, dtype=np.float64)
        if p.shape[-1:] != (self.n_params,):
            raise ValueError(f"params have shape {p.shape}, expected (..., {self.n_params})")
        lead = p.shape[:-1]
        layers: list[Layer] = []
        at = 0
        for k, (o, i) in enumerate(self.layer_shapes()):
            W = p[..., at:at + o * i].reshape(*lead, o, i)
            at += o * i
            b = None
            if self.layer_has_bias(k):
                b = p[..., at:at + o]
                at += o
            layers.append((W, b))
        return layers

    def flatten(self, layers: list[Layer]) -> np.ndarray:
        """Inverse of :meth:`unflatten` for one policy."""
        parts = []
        for (W, b), (o, i), k in zip(layers, self.layer_shapes(), range(len(layers)),
                                     strict=True):
            parts.append(np.asarray(W, dtype=np.float64).reshape(o * i))
            if self.layer_has_bias(k):
                parts.append(np.asarray(b, dtype=np.float64).reshape(o))
        return np.concatenate(parts)

    def normalise(self, obs: np.ndarray, mean: np.ndarray, std: np.ndarray) -> np.ndarray:
        """``clip((obs − mean) / std, ±clip_obs)`` (ARS V2, Algorithm 2 line 5)."""
        x = (np.asarray(obs, dtype=np.float64) - mean) / std
        return np.clip(x, -self.clip_obs, self.clip_obs) if math.isfinite(self.clip_obs) else x

    def act(self, params: np.ndarray, obs: np.ndarray, mean: np.ndarray, std: np.ndarray
            ) -> np.ndarray:
        """``actions[n, a]`` of ``n`` policies ``params[n, P]`` on their ``obs[n, o]``
        (``mean``/``std``: one normaliser ``(o,)`` or one per row ``(n, o)``)."""
        obs = self._check_act(params, obs, mean, std)
        h = self.normalise(obs, mean, std)
        layers = self.unflatten(params)
        for k, (W, b) in enumerate(layers):
            h = np.matmul(W, h[..., None])[..., 0]
            if b is not None:
                h = h + b
            if k < len(layers) - 1 or self.squash_output:
                h = np.tanh(h)
        return np.clip(self.offset + self.scale * h, self.low, self.high)

    def _check_act(self, params: np.ndarray, obs: np.ndarray, mean: np.ndarray,
                   std: np.ndarray) -> np.ndarray:
        """``obs`` as float64 ``[n, o]`` once the shapes of :meth:`act`'s arguments agree."""
        obs = np.asarray(obs, dtype=np.float64)
        if obs.ndim != 2 or obs.shape[1] != self.obs_dim:
            raise ValueError(f"obs has shape {obs.shape}, expected (n, {self.obs_dim})")
        if np.shape(params)[:-1] != obs.shape[:1]:
            raise ValueError(f"{np.shape(params)[0] if np.ndim(params) else 0} parameter rows "
                             f"for {obs.shape[0]} observations")
        shapes = ((self.obs_dim,), obs.shape)
        if np.shape(mean) not in shapes or np.shape(std) not in shapes:
            raise ValueError(f"mean/std have shapes {np.shape(mean)}/{np.shape(std)}, "
                             f"expected ({self.obs_dim},) or {obs.shape}")
        return obs

    def act_one(self, params: np.ndarray, obs: np.ndarray, mean: np.ndarray, std: np.ndarray
                ) -> np.ndarray:
        """``action[a]`` of one policy ``params[P]`` on one ``obs[o]``."""
        return self.act(np.asarray(params)[None], np.asarray(obs)[None], mean, std)[0]

    def genome_bounds(self, bound: float = 10.0) -> tuple[np.ndarray, np.ndarray]:
        """A wide box ``±bound`` on every parameter (its middle, 0, is the ES's start)."""
        if not bound > 0 or not math.isfinite(bound):
            raise ValueError(f"bound must be finite and > 0, got {bound!r}")
        return np.full(self.n_params, -float(bound)), np.full(self.n_params, float(bound))

    def initial_params(self, rng: np.random.Generator) -> np.ndarray:
        """The centre the search starts from (zeros unless a kind says otherwise)."""
        return np.zeros(self.n_params)
