"""Policies as flat parameter vectors: what a closed-loop rollout calls at every control step.

- :mod:`.normalizer`: running observation statistics (ARS V2), explicit and mergeable;
- :mod:`.spec`: the shared action map, parameter layout and batched forward pass;
- :mod:`.linear`: static linear policies (ARS); :mod:`.mlp`: tanh MLPs;
- :mod:`.structured`: a gait's phase generator (Fourier tape) plus linear feedback;
- :mod:`.export`: ``policy.npz``, a numpy-only ``policy.py`` and ``policy.onnx``, and the
  reader of ``policy.npz``.

:data:`POLICIES` maps a name to its spec class; :func:`make_policy` builds one with a one-line
error for an unknown name or option.
"""

from __future__ import annotations

import dataclasses
from typing import Any

from evomotion.core.policies.linear import LinearSpec
from evomotion.core.policies.mlp import MLPSpec
from evomotion.core.policies.spec import PolicySpec
from evomotion.core.policies.structured import StructuredSpec, fit_tape
from evomotion.core.registry import lookup

POLICIES: dict[str, type[PolicySpec]] = {"linear": LinearSpec, "mlp": MLPSpec,
                                          "structured": StructuredSpec}


def make_policy(kind: str, obs_dim: int, act_dim: int, **options: Any) -> PolicySpec:
    """The spec of policy ``kind`` (see :data:`POLICIES`); bad options raise ``ValueError``."""
    cls = lookup(POLICIES, "policy", kind)
    names = {f.name for f in dataclasses.fields(cls)} - {"obs_dim", "act_dim"}
    unknown = sorted(set(options) - names)
    if unknown:
        raise ValueError(f"unknown option {unknown[0]!r} for the {kind} policy; available: "
                         f"{', '.join(sorted(names))}")
    return cls(obs_dim=obs_dim, act_dim=act_dim, **options)


__all__ = ["POLICIES", "LinearSpec", "MLPSpec", "PolicySpec", "StructuredSpec", "fit_tape",
           "make_policy"]
