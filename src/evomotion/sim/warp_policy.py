"""A population's policies as one callable, and their forward pass on a Warp device.

:class:`PopulationPolicy` is the closed loop's ``policy(rows, obs) -> actions`` for ``n``
policies of one :class:`~evomotion.core.policies.spec.PolicySpec`, row ``i`` with its own
parameters and normaliser; on the host it is :meth:`PolicySpec.act`. The Warp closed loop
(:mod:`evomotion.sim.warp_closed_loop`) recognises it and, for the linear and MLP specs (whose
forward pass is :meth:`PolicySpec.act` itself), evaluates it on the device instead, every
world with its own weights (``W[world, out, in]``, read through ``spec.unflatten``) in float32:

    x = clip((obs - mean) / std, -clip_obs, clip_obs)     # normalise
    h = tanh(W_i h + b_i)                                   # hidden layers, one thread per unit
    action = clip(offset + scale * y, low, high)            # y = W_L h + b_L (tanh: MLP)

Any other policy (a plain callable, the structured spec) runs on the host.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, TypeGuard

import numpy as np

from evomotion.core.policies.linear import LinearSpec
from evomotion.core.policies.mlp import MLPSpec
from evomotion.core.policies.spec import PolicySpec


@dataclass(frozen=True, eq=False)
class PopulationPolicy:
    """``n`` policies of ``spec``: ``params[n, P]``, normalisers ``mean``/``std`` ``[n, o]``
    (or ``(o,)`` for all); called with ``(rows, obs[m, o])`` it acts for those rows."""

    spec: PolicySpec
    params: np.ndarray
    mean: np.ndarray
    std: np.ndarray

    def __post_init__(self) -> None:
        p = np.atleast_2d(np.asarray(self.params, dtype=np.float64))
        n, o = p.shape[0], self.spec.obs_dim
        mean = np.broadcast_to(np.asarray(self.mean, dtype=np.float64), (n, o))
        std = np.broadcast_to(np.asarray(self.std, dtype=np.float64), (n, o))
        self.spec.unflatten(p)  # one-line ValueError for a wrong parameter count
        object.__setattr__(self, "params", p)
        object.__setattr__(self, "mean", mean)
        object.__setattr__(self, "std", std)

    def __call__(self, rows: np.ndarray, obs: np.ndarray) -> np.ndarray:
        return self.spec.act(self.params[rows], obs, self.mean[rows], self.std[rows])


def on_device(policy: Any) -> TypeGuard[PopulationPolicy]:
    """Whether ``policy``'s forward pass can run on the device (a :class:`PopulationPolicy`
    of a linear or MLP spec that does not override the shared forward pass)."""
    return (isinstance(policy, PopulationPolicy)
            and isinstance(policy.spec, LinearSpec | MLPSpec)
            and type(policy.spec).act is PolicySpec.act)


_BIG = 3.0e38  # "no clipping" in float32


class DeviceLayers:
    """The device buffers of one spec's forward pass for ``nworld`` worlds."""

    def __init__(self, wp: Any, spec: PolicySpec, nworld: int) -> None:
        self.wp, self.spec, self.nworld = wp, spec, nworld
        f32, o = wp.float32, spec.obs_dim
        self.mean = wp.zeros((nworld, o), dtype=f32)
        self.std = wp.ones((nworld, o), dtype=f32)
        self.x = wp.zeros((nworld, o), dtype=f32)
        self.weights, self.biases, self.hidden = [], [], []
        for k, (out, inp) in enumerate(spec.layer_shapes()):
            self.weights.append(wp.zeros((nworld, out, inp), dtype=f32))
            self.biases.append(wp.zeros((nworld, out if spec.layer_has_bias(k) else 1),
                                        dtype=f32))
            self.hidden.append(wp.zeros((nworld, out), dtype=f32))
        vec = [np.broadcast_to(np.asarray(v, np.float32), (spec.act_dim,)).copy()
               for v in (spec.scale, spec.offset, np.clip(spec.low, -_BIG, _BIG),
                         np.clip(spec.high, -_BIG, _BIG))]
        self.scale, self.offset, self.low, self.high = (wp.array(v, dtype=f32) for v in vec)
        self.clip = float(min(spec.clip_obs, _BIG)) if math.isfinite(spec.clip_obs) else _BIG

    def load(self, policy: PopulationPolicy, rows: np.ndarray) -> None:
        """The parameters and normalisers of ``rows`` (one per world) onto the device."""
        layers = self.spec.unflatten(policy.params[rows])
        for k, (W, b) in enumerate(layers):
            self.weights[k].assign(np.ascontiguousarray(W, dtype=np.float32))
            if b is not None:
                self.biases[k].assign(np.ascontiguousarray(b, dtype=np.float32))
        self.mean.assign(np.ascontiguousarray(policy.mean[rows], dtype=np.float32))
        self.std.assign(np.ascontiguousarray(policy.std[rows], dtype=np.float32))

    def launch(self, obs: Any, actions: Any) -> None:
        """``actions[nworld, a]`` of every world's policy on ``obs[nworld, o]``."""
        from evomotion.sim import warp_closed_loop_kernels as kern

        wp = self.wp
        n, last = self.nworld, len(self.weights) - 1
        wp.launch(kern.normalise, dim=(n, self.spec.obs_dim),
                  inputs=[obs, self.mean, self.std, self.clip], outputs=[self.x])
        h = self.x
        for k, (W, b, y) in enumerate(zip(self.weights, self.biases, self.hidden,
                                          strict=True)):
            squash = int(k < last or self.spec.squash_output)
            wp.launch(kern.dense, dim=(n, W.shape[1]),
                      inputs=[W, b, int(self.spec.layer_has_bias(k)), squash, h], outputs=[y])
            h = y
        wp.launch(kern.action_map, dim=(n, self.spec.act_dim),
                  inputs=[h, self.scale, self.offset, self.low, self.high], outputs=[actions])
