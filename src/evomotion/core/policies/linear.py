"""Static linear policies, as in ARS.

Mania, Guy & Recht 2018, "Simple random search provides a competitive approach to reinforcement
learning" (arXiv 1803.07055): V1 acts with ``a = M s``, V2 with
``a = M diag(Σ)^(-1/2) (s − μ)`` (Algorithm 2, line 5; the normalisation is
:mod:`evomotion.core.policies.normalizer`), ``M`` an ``act_dim x obs_dim`` matrix started at 0.
Here the output goes through the action map, ``clip(offset + scale * M x, low, high)``, with no
squashing (ARS has none). ``bias=True`` adds a bias ``b`` (``M x + b``; ARS has none).

Parameters: ``M`` row-major (``params[i * obs_dim + j] = M[i, j]``), then ``b`` if any.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from evomotion.core.policies.spec import PolicySpec


@dataclass(frozen=True, eq=False)
class LinearSpec(PolicySpec):
    """A linear policy ``clip(offset + scale * (M x [+ b]), low, high)``; P = a·o (+ a)."""

    bias: bool = False

    kind: ClassVar[str] = "linear"
    squash_output: ClassVar[bool] = False

    def __post_init__(self) -> None:
        super().__post_init__()
        if not isinstance(self.bias, bool):
            raise ValueError(f"bias must be true or false, got {self.bias!r}")

    def layer_shapes(self) -> list[tuple[int, int]]:
        return [(self.act_dim, self.obs_dim)]

    def layer_has_bias(self, i: int) -> bool:
        return self.bias
