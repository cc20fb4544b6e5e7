"""Multi-layer perceptrons with tanh hidden layers and a tanh-squashed output.

``h_1 = tanh(W_1 x + b_1)``, ..., ``y = tanh(W_L h_{L-1} + b_L)``, then the action map
``clip(offset + scale * y, low, high)``: with ``offset`` a nominal pose and ``scale`` a joint
range's half-width the action covers ``offset ± scale`` and no more, whatever the weights.

Initialisation (:meth:`MLPSpec.initial_params`): Glorot & Bengio 2010, "Understanding the
difficulty of training deep feedforward neural networks" (AISTATS), the normalised
initialisation of their eq. 16, ``W ~ U[−√6/√(n_in + n_out), +√6/√(n_in + n_out)]``, derived
for tanh units; biases 0.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from evomotion.core.policies.spec import Layer, PolicySpec


@dataclass(frozen=True, eq=False)
class MLPSpec(PolicySpec):
    """An MLP with tanh hidden layers of sizes ``hidden`` (at least one) and a tanh output."""

    hidden: tuple[int, ...] = (64, 64)

    kind: ClassVar[str] = "mlp"
    squash_output: ClassVar[bool] = True

    def __post_init__(self) -> None:
        super().__post_init__()
        try:
            hidden = tuple(self.hidden)
        except TypeError:
            raise ValueError(f"hidden must be a list of layer sizes, got {self.hidden!r}"
                             ) from None
        if not hidden or any(isinstance(h, bool) or not isinstance(h, int | np.integer)
                             or h < 1 for h in hidden):
            raise ValueError(f"hidden must be one or more whole numbers >= 1, got {hidden!r}")
        object.__setattr__(self, "hidden", tuple(int(h) for h in hidden))

    def layer_shapes(self) -> list[tuple[int, int]]:
        sizes = [self.obs_dim, *self.hidden, self.act_dim]
        return [(sizes[k + 1], sizes[k]) for k in range(len(sizes) - 1)]

    def initial_params(self, rng: np.random.Generator) -> np.ndarray:
        """Glorot-uniform weights (eq. 16 of Glorot & Bengio 2010), zero biases."""
        layers: list[Layer] = []
        for o, i in self.layer_shapes():
            limit = math.sqrt(6.0 / (i + o))
            layers.append((rng.uniform(-limit, limit, size=(o, i)), np.zeros(o)))
        return self.flatten(layers)
