"""A policy as an ONNX graph (opset 17, float32), normalisation inside.

Input ``observation`` float32 ``[batch, obs_dim]``, output ``action`` float32
``[batch, act_dim]``; the nodes follow :meth:`PolicySpec.act`::

    Sub(observation, obs_mean) -> Div(obs_std) -> Clip(−clip_obs, clip_obs)   (if finite)
    Gemm(h, W_k, b_k, transB=1) (MatMul(h, W_kᵀ) without a bias) -> Tanh      per layer
    Mul(action_scale) -> Add(action_offset) -> Max(action_low) -> Min(action_high) -> action

(``Clip`` takes scalar bounds only, hence ``Max``/``Min`` for the per-joint action bounds.)
A structured policy (:mod:`.structured`) replaces the layers by its tape and gains::

    Gather(observation, sin/cos column) -> s_1, c_1 [batch, 1]         (raw, not normalised)
    s_{k+1} = Add(Mul(s_k, c_1), Mul(c_k, s_1)), c_{k+1} = Sub(Mul(c_k, c_1), Mul(s_k, s_1))
    g = Concat(1, s_1, c_1, ..., s_H, c_H)                             ([batch, 1 + 2H])
    g = Concat(g, Mul(g, command_1), ..., Mul(g, command_m))           (with command_columns;
        command_i = Gather(observation) + Gather(MatMul(x, G^T), i)      with command feedback)
    tape = MatMul(g, Cᵀ)                                                ([batch, act])
    Gather(normalised, other columns) -> MatMul(Kᵀ) -> Add(tape)        (the feedback)
Built with ``onnx.helper``; needs the ``onnx`` extra (``pip install evomotion[onnx]``).
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from evomotion.core.policies.spec import Layer, PolicySpec
from evomotion.core.policies.structured import StructuredSpec

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
        a = np.asarray(value)  # indices stay int64, numbers become float32
        inits.append(numpy_helper.from_array(
            a if a.dtype == np.int64 else a.astype(np.float32), name))
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
    if isinstance(spec, StructuredSpec):
        h = _structured(spec, layers, h, const, node)
        layers = []
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


def _structured(spec: StructuredSpec, layers: list[Layer], normalised: str, const, node) -> str:
    """The nodes of ``tape(φ, c) + K x`` (see the module doc); returns the output's name."""
    (C, _), (K, _) = layers[:2]
    i, j = spec.phase_columns  # type: ignore[misc]
    x = None
    if K.shape[1]:
        x = node("Gather", [normalised, const("feedback_columns",
                                              spec.feedback_columns.astype(np.int64))],
                 "feedback_input", axis=1)
    shift = None
    if spec.command_feedback and x is not None:  # c' = c + G x
        shift = node("MatMul", [x, const("command_gain_t", layers[2][0].T)], "command_shift")
    s1 = node("Gather", ["observation", const("phase_sin_column", np.array([i], np.int64))],
              "phase_sin_1", axis=1)
    c1 = node("Gather", ["observation", const("phase_cos_column", np.array([j], np.int64))],
              "phase_cos_1", axis=1)
    one = node("Add", [node("Mul", [s1, const("zero", np.zeros(1))], "zero_batch"),
                       const("one", np.ones(1))], "phase_one")
    f = [one]
    s, c = s1, c1
    for k in range(1, spec.harmonics + 1):
        if k > 1:
            sc, cs = node("Mul", [s, c1], f"sc_{k}"), node("Mul", [c, s1], f"cs_{k}")
            cc, ss = node("Mul", [c, c1], f"cc_{k}"), node("Mul", [s, s1], f"ss_{k}")
            s, c = node("Add", [sc, cs], f"phase_sin_{k}"), node("Sub", [cc, ss], f"phase_cos_{k}")
        f += [s, c]
    g = node("Concat", f, "phase_features", axis=1)
    parts = [g]
    for m, col in enumerate(spec.command_columns):
        cm = node("Gather", ["observation", const(f"command_column_{m}",
                                                  np.array([col], np.int64))],
                  f"command_{m}", axis=1)
        if shift is not None:
            dm = node("Gather", [shift, const(f"command_index_{m}", np.array([m], np.int64))],
                      f"command_shift_{m}", axis=1)
            cm = node("Add", [cm, dm], f"command_fed_back_{m}")
        parts.append(node("Mul", [g, cm], f"command_features_{m}"))
    if len(parts) > 1:
        g = node("Concat", parts, "tape_features", axis=1)
    y = node("MatMul", [g, const("tape_coef_t", C.T)], "tape")
    if x is None:
        return y
    fb = node("MatMul", [x, const("feedback_gain_t", K.T)], "feedback")
    return node("Add", [y, fb], "structured_output")
