"""A policy as an ONNX graph (opset 17, float32), normalisation inside.

Input ``observation`` float32 ``[batch, obs_dim]``, output ``action`` float32
``[batch, act_dim]``; the nodes follow :meth:`PolicySpec.act`::

    Sub(observation, obs_mean) -> Div(obs_std) -> Clip(−clip_obs, clip_obs)   (if finite)
    Gemm(h, W_k, b_k, transB=1) (MatMul(h, W_kᵀ) without a bias) -> Tanh      per layer
    Mul(action_scale) -> Add(action_offset) -> Max(action_low) -> Min(action_high) -> action

(``Clip`` takes scalar bounds only, hence ``Max``/``Min`` for the per-joint action bounds.)
Built with ``onnx.helper``; needs the ``onnx`` extra (``pip install evomotion[onnx]``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from evomotion.core.policies.spec import PolicySpec

OPSET = 17
IR_VERSION = 8  # the IR version of opset 17 (ONNX 1.12): readable by older runtimes too


def policy_model(spec: PolicySpec, params: np.ndarray, obs_mean: np.ndarray,
                 obs_std: np.ndarray) -> Any:
    """The checked ``onnx.ModelProto`` of the policy ``params`` with these statistics."""
    try:
        import onnx
        from onnx import TensorProto, helper, numpy_helper
    except ImportError:
        raise ValueError("writing policy.onnx needs the onnx package "
                         "(pip install 'evomotion[onnx]')") from None
    inits: list[Any] = []
    nodes: list[Any] = []

    def const(name: str, value) -> str:
        inits.append(numpy_helper.from_array(np.asarray(value, dtype=np.float32), name))
        return name

    def node(op: str, inputs: list[str], output: str, **attrs) -> str:
        nodes.append(helper.make_node(op, inputs, [output], name=output, **attrs))
        return output

    h = node("Sub", ["observation", const("obs_mean", obs_mean)], "centred")
    h = node("Div", [h, const("obs_std", obs_std)], "normalised")
    if math.isfinite(spec.clip_obs):
        h = node("Clip", [h, const("clip_low", -spec.clip_obs),
                          const("clip_high", spec.clip_obs)], "clipped")
    layers = spec.unflatten(np.asarray(params, dtype=np.float64))
    for k, (W, b) in enumerate(layers):
        if b is not None:
            h = node("Gemm", [h, const(f"layer{k}_weight", W), const(f"layer{k}_bias", b)],
                     f"layer{k}_linear", transB=1)
        else:
            h = node("MatMul", [h, const(f"layer{k}_weight_t", W.T)], f"layer{k}_linear")
        if k < len(layers) - 1 or spec.squash_output:
            h = node("Tanh", [h], f"layer{k}_tanh")
    h = node("Mul", [h, const("action_scale", spec.scale)], "scaled")
    h = node("Add", [h, const("action_offset", spec.offset)], "unclipped")
    h = node("Max", [h, const("action_low", spec.low)], "above_low")
    node("Min", [h, const("action_high", spec.high)], "action")
    graph = helper.make_graph(
        nodes, f"evomotion_{spec.kind}_policy",
        [helper.make_tensor_value_info("observation", TensorProto.FLOAT,
                                       ["batch", spec.obs_dim])],
        [helper.make_tensor_value_info("action", TensorProto.FLOAT, ["batch", spec.act_dim])],
        initializer=inits)
    model = helper.make_model(graph, producer_name="evomotion",
                              opset_imports=[helper.make_opsetid("", OPSET)])
    model.ir_version = IR_VERSION
    onnx.checker.check_model(model)
    return model
