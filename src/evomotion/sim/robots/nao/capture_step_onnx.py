"""The walk's capture step as an ONNX graph with explicit state, and the walk controller
(policy + capture step) as one model, ``controller.onnx``.

The same arithmetic as ``evomotion.studies.humanoid_omniwalk.capture_step`` (its docstring has
the equations) and :mod:`.naoqi_capture_step` (the standard-library layer the NAOqi runner
loads): leg odometry ``v = −(ω × p(q) + J(q) q̇)`` from the NAO's closed-form leg kinematics
(:mod:`.leg_ik`, paper 002, Graf et al. 2009; ``J q̇`` as the finite difference
``(p(q + ε q̇) − p(q)) / ε``, ε = 1e-4, as both), the velocity's offset from the command and
from the walk's own sway by phase bin (learnt online), a dead band, and the swing foot's
landing point moved by ``gain Δv / ω₀`` (the capture point, Pratt et al., Humanoids 2006)
through the walk engine's closed-form leg IK (``omni_gait.targets``' arithmetic with
``foot_offsets``; the engine's settings, the leg geometry and ranges in the record). Built with
``onnx.helper`` (opset 17, IR 8) from :mod:`.onnx_kinematics`; computed in float64 (the
odometry's ε is useless in float32), the observation and action cast at the edges. Everything
comes from the record (``policy.json``'s ``layers.capture_step``), like the NAOqi layer.

:func:`capture_step_model`: inputs ``observation [batch, obs]`` float32 (the raw observation
the policy reads), ``action [batch, act]`` float32 (the policy's output), ``state_in [batch,
S]`` float64; outputs ``action_out [batch, act]`` float32 (the action with the feet moved) and
``state_out [batch, S]`` float64, fed back as the next step's ``state_in``. Each row is one
robot. :func:`controller_model` is the policy and the layer in one graph: inputs
``observation``, ``state_in``; outputs ``action``, ``state_out``. The state's layout
(:func:`state_layout`, ``S = 2 bins + 13``; it starts at zeros, :func:`initial_state`):

- ``sway`` [0, 2 bins): the learnt ``v̄`` (m/s) per phase bin, ``x, y`` per bin;
- ``steps``: the layer's calls so far (it acts after ``warmup_cycles · bins``);
- ``offset``, ``lift_off`` (4 each): the feet's landing offsets now and at lift-off (m;
  left x, left y, right x, right y);
- ``swinging`` (2): 1 while the left, right foot swings;
- ``hip_yaw_pitch``: the last finite LHipYawPitch action (rad from its nominal angle; the
  odometry's hip yaw-pitch is its nominal plus this), ``hip_yaw_pitch_rate`` (rad/s).
"""

from __future__ import annotations

import json
import math
from typing import Any

import numpy as np

from evomotion.core.policies.onnx_graph import IR_VERSION, OPSET
from evomotion.sim.robots.nao import onnx_kinematics as ox
from evomotion.sim.robots.nao.naoqi_capture_step import EPS, LEGS, READS, check
from evomotion.sim.robots.nao.onnx_kinematics import Graph, V, apply, clip, where

PREFIX = "capture_step/"
STATE_PARTS = (("sway", None), ("steps", 1), ("offset", 4), ("lift_off", 4), ("swinging", 2),
               ("hip_yaw_pitch", 1), ("hip_yaw_pitch_rate", 1))


def state_layout(record: dict[str, Any]) -> dict[str, list[int]]:
    """``{part: [start, stop)}`` of the flat state (module doc) for ``record``'s bins."""
    out, at = {}, 0
    for name, size in STATE_PARTS:
        n = 2 * int(record["bins"]) if size is None else size
        out[name], at = [at, at + n], at + n
    return out


def initial_state(record: dict[str, Any], batch: int = 1) -> np.ndarray:
    """The state's start, ``[batch, S]`` float64 zeros (a new walk starts from it)."""
    return np.zeros((batch, state_layout(record)["hip_yaw_pitch_rate"][1]))


def _onnx() -> Any:
    try:
        import onnx
    except ImportError:
        raise ValueError("the capture step's ONNX graph needs the onnx package "
                         "(pip install 'evomotion[onnx]')") from None
    return onnx


def _idx(g: Graph, *i: int) -> V:
    return g.tensor(g.const(np.array(i, np.int64)))


def _take(x: V, i: int, axis: int) -> V:
    return apply("Gather", x, _idx(x.g, i), axis=axis)


def _reduce_sum(x: V, axis: int) -> V:
    return apply("ReduceSum", x, _idx(x.g, axis), keepdims=1)


def _shape(x: V, *dims: int) -> V:
    return apply("Reshape", x, _idx(x.g, -1, *dims))


def _cat(axis: int, *xs: V) -> V:
    return apply("Concat", *xs, axis=axis)


def _layer(g: Graph, record: dict[str, Any], names: list[str], joints: list[str],
           nominal: list[float], control_period_s: float, obs_in: str, action_in: str,
           state_in: str) -> tuple[str, str]:
    """The layer's nodes into ``g``; returns (the action, the state) as float64 names."""
    check(record)
    col = {n: i for i, n in enumerate(names)}
    missing = [n for n in READS if n not in col]
    if missing:
        raise ValueError(f"capture_step: it reads observation {missing[0]!r}, which the "
                         "policy does not")
    if "LHipYawPitch" not in joints or len(nominal) != len(joints):
        raise ValueError("capture_step: expected LHipYawPitch among the joints, with a "
                         "nominal angle each")
    gait, bins, dt = record["gait"], int(record["bins"]), float(control_period_s)
    if not (math.isfinite(dt) and dt > 0):
        raise ValueError(f"capture_step: control_period_s {control_period_s!r}: expected a "
                         "positive number of seconds")
    w, period = float(gait["swing_fraction"]), float(gait["period_s"])
    leg = ox.Leg(record["geometry"])
    obs = apply("Unsqueeze", ox.to_double(g.tensor(obs_in)), _idx(g, 2))  # [B, O, 1]

    def cols(*keys: str) -> V:  # observation columns as feet: [B, len(keys), 1]
        return apply("Gather", obs, _idx(g, *(col[k] for k in keys)), axis=1)

    def feet(key: str, k: int) -> V:  # a left/right leg joint's column, e.g. joint_pos:
        return cols(key + LEGS["left"][k], key + LEGS["right"][k])

    layout, state = state_layout(record), g.tensor(state_in)

    def part(name: str, *dims: int) -> V:
        a, b = layout[name]
        return _shape(apply("Slice", state, _idx(g, a), _idx(g, b), _idx(g, 1)), *dims)

    table, steps = part("sway", bins, 2), part("steps", 1, 1)
    off, lift = part("offset", 2, 2), part("lift_off", 2, 2)
    swinging, hyp_state = ox.gt(part("swinging", 2, 1), 0.5), part("hip_yaw_pitch", 1)
    hyp_nominal = float(nominal[joints.index("LHipYawPitch")])
    # the gait phase, its bin and each foot's phase p (left φ, right φ + 1/2)
    phase = ox.mod(ox.atan2(cols("phase:sin"), cols("phase:cos")) / (2 * np.pi), 1.0)
    cx, cy, cw = (cols(f"command:{i}") for i in range(3))
    p = ox.mod(phase + np.array([[0.0], [0.5]]), 1.0)  # [B, 2, 1]
    r = apply("Round", phase * bins)
    onehot = ox.eq(where(ox.ge(r, bins), r - bins, r), np.arange(bins, dtype=float)[:, None])
    sway = _reduce_sum(where(onehot, table, 0.0), 1)  # [B, 1, 2]
    sx, sy = _take(sway, 0, 2), _take(sway, 1, 2)
    # eq. (1): leg odometry at q and q + ε q̇ (the variants' axis), both feet at once
    hyp = hyp_nominal + _shape(hyp_state, 1, 1)
    q = [hyp] + [feet("joint_pos:", k) for k in (1, 2, 3)]
    dq = [_shape(part("hip_yaw_pitch_rate", 1), 1, 1)] + [feet("joint_vel:", k)
                                                          for k in (1, 2, 3)]
    pos = leg.ankle([_cat(2, a, a + EPS * b) for a, b in zip(q, dq, strict=True)])
    p0, p1 = [_take(c, 0, 2) for c in pos], [_take(c, 1, 2) for c in pos]
    wx, wy, wz = (cols(f"gyro:{a}") for a in "xyz")
    est = [-(wy * p0[2] - wz * p0[1] + (p1[0] - p0[0]) / EPS),
           -(wz * p0[0] - wx * p0[2] + (p1[1] - p0[1]) / EPS)]
    touch = ox.gt(cols("foot_contact:left", "foot_contact:right"), 0.5)
    anyone = apply("Or", _take(touch, 0, 1), _take(touch, 1, 1))
    weight = where(anyone, ox.to_double(touch), ox.to_double(ox.ge(p, w)))  # (no bool Where)
    weight = weight / apply("Max", _reduce_sum(weight, 1), 1.0)
    vx, vy = (_reduce_sum(where(ox.gt(weight, 0.0), weight * e, 0.0), 1) for e in est)
    # eq. (2), the sway's calibration, the warm-up and the dead band
    dvx, dvy = vx - cx - sx, vy - cy - sy
    ok = apply("And", ox.finite(dvx), ox.finite(dvy))
    dvx, dvy = where(ok, dvx, 0.0), where(ok, dvy, 0.0)
    steps = steps + 1.0
    calm = ox.lt(apply("Sqrt", dvx * dvx + dvy * dvy), float(record["calibration_gate_mps"]))
    rate = float(record["calibration_rate"])
    table = where(apply("And", onehot, calm), _cat(2, sx + rate * dvx, sy + rate * dvy), table)
    # whole cycles, as the NAOqi layer's int(); the record's check allows any number
    warm = ox.gt(steps, float(int(record["warmup_cycles"]) * bins))
    dvx, dvy = where(warm, dvx, 0.0), where(warm, dvy, 0.0)
    size = apply("Sqrt", dvx * dvx + dvy * dvy)
    shrink = apply("Max", size - float(record["deadband_mps"]), 0.0)
    grow = apply("Max", size, 1e-12)
    gain, omega = g.named(float(record["gain"]), "gain"), math.sqrt(
        9.81 / float(record["com_height_m"]))
    land_x, land_y = (gain * (d * shrink / grow) / omega for d in (dvx, dvy))
    # the swing foot's landing offset: from its lift-off offset to the goal on a cosine
    side = np.array([[1.0], [-1.0]])
    off_x, off_y, lo_x, lo_y = _take(off, 0, 2), _take(off, 1, 2), _take(lift, 0, 2), \
        _take(lift, 1, 2)
    swing = ox.lt(p, w)
    new = apply("And", swing, apply("Not", swinging))
    lo_x, lo_y = where(new, off_x, lo_x), where(new, off_y, lo_y)
    reach = float(record["reach_x_m"])
    goal_x = clip(land_x, -reach, reach)
    goal_y = side * clip(side * land_y, -float(record["in_y_m"]), float(record["out_y_m"]))
    a = 0.5 * (1.0 - apply("Cos", np.pi * clip((p + dt / period) / w, 0.0, 1.0)))
    off_x = where(swing, lo_x + (goal_x - lo_x) * a, off_x)
    off_y = where(swing, lo_y + (goal_y - lo_y) * a, off_y)
    # the engine's leg angles with the feet moved (variant 1) less without (variant 0)
    delta = _engine(g, record, leg, phase, p, (cx, cy, cw), off_x, off_y, joints)
    out = ox.to_double(g.tensor(action_in)) + delta
    a_hyp = _take(out, joints.index("LHipYawPitch"), 1)
    ok = ox.finite(a_hyp)  # a NaN action: the motor holds its last target
    rate_out = where(ok, ((hyp_nominal + a_hyp) - (hyp_nominal + hyp_state)) / dt, 0.0)
    state_out = _cat(1, _shape(table, 2 * bins), _shape(steps, 1),
                     _shape(_cat(2, off_x, off_y), 4), _shape(_cat(2, lo_x, lo_y), 4),
                     _shape(ox.to_double(swing), 2), where(ok, a_hyp, hyp_state), rate_out)
    return out.ref, state_out.ref


def _engine(g: Graph, record: dict[str, Any], leg: ox.Leg, phase: V, p: V,
            command: tuple[V, V, V], off_x: V, off_y: V, joints: list[str]) -> V:
    """``targets(phase, command, offsets) − targets(phase, command, 0)`` at ``joints`` ([B,
    act]; the legs', and NaN on a shoulder pitch where the arm swing is NaN, as numpy's)."""
    gait, s = record["gait"], leg.s
    w = float(gait["swing_fraction"])
    k = 1.0 - w
    dx, dy, dpsi = (c * k * float(gait["period_s"]) for c in command)
    swing = ox.lt(p, w)
    st = where(swing, p / w, 0.0)
    u = where(swing, -0.5 + 0.5 * (1.0 - apply("Cos", np.pi * st)),
              0.5 - where(swing, 0.0, (p - w) / (1.0 - w)))
    lift = where(swing, 0.5 * (1.0 - apply("Cos", 2.0 * np.pi * st)), 0.0)
    rel_yaw = (_take(u, 0, 1) - _take(u, 1, 1)) * dpsi
    wave = 2 * np.pi * (phase - 0.5 * w)
    sway = -float(gait["sway_m"]) * apply("Cos", wave + float(gait["sway_phase_rad"]))
    lean = ox.transpose(ox.rotation(float(gait["lean_rad"]), 1))
    moved = np.array([[False, True]])  # the variants: plain, moved
    yaw = s * 0.5 * rel_yaw
    x = float(gait["x_offset_m"]) + u * dx + where(moved, off_x, 0.0)
    y = s * (leg.hip_y + float(gait["width_m"])) + u * dy + sway + where(moved, off_y, 0.0)
    c, sn = apply("Cos", yaw), apply("Sin", yaw)
    pos = [c * x - sn * y, sn * x + c * y,
           -(leg.hip_z + float(gait["leg_height_m"])) + lift * float(gait["step_height_m"])]
    q = leg.ik(ox.matvec(lean, pos), ox.matmul(lean, ox.rotation(yaw, 2)))
    q[0] = _take(q[0], 0, 1)  # RHipYawPitch = LHipYawPitch (one motor), then clipped
    deltas = []
    for i, qi in enumerate(q):
        lo, hi = (np.array([[record["ranges"][LEGS[f][i]][b]] for f in ("left", "right")],
                           float) for b in (0, 1))
        qc = clip(qi, lo, hi)
        deltas.append(_take(qc, 1, 2) - _take(qc, 0, 2))
    arm = float(gait.get("arm_swing_rad_per_mps", 0.0)) * command[0] * apply("Cos", wave)
    shoulder = where(apply("IsNaN", arm), np.nan, 0.0)
    every = _cat(1, _shape(_cat(2, *deltas), 12), _shape(shoulder, 1))  # [B, 13]
    index = {j: 6 * f + i for f, side in enumerate(("left", "right"))
             for i, j in enumerate(LEGS[side])}
    index.update(LShoulderPitch=12, RShoulderPitch=12)
    picked = apply("Gather", every, _idx(g, *(index.get(j, 0) for j in joints)), axis=1)
    return where(np.array([j in index for j in joints]), picked, 0.0)


def _graph_io(onnx: Any, inputs: list[tuple[str, int, int]],
              outputs: list[tuple[str, int, int]]) -> tuple[list[Any], list[Any]]:
    h = onnx.helper
    return ([h.make_tensor_value_info(n, t, ["batch", d]) for n, t, d in inputs],
            [h.make_tensor_value_info(n, t, ["batch", d]) for n, t, d in outputs])


def _model(onnx: Any, nodes: list[Any], inits: list[Any], name: str, io: tuple,
           record: dict[str, Any]) -> Any:
    h = onnx.helper
    model = h.make_model(h.make_graph(nodes, name, io[0], io[1], initializer=inits),
                         producer_name="evomotion", opset_imports=[h.make_opsetid("", OPSET)])
    model.ir_version = IR_VERSION
    h.set_model_props(model, {"capture_step_state_layout": json.dumps(state_layout(record)),
                              "capture_step_state_start": "zeros"})
    onnx.checker.check_model(model)
    return model


def capture_step_model(record: dict[str, Any], names: list[str], joints: list[str],
                       nominal: list[float], control_period_s: float) -> Any:
    """The checked ``onnx.ModelProto`` of the layer (module doc) for a policy reading
    ``names`` and setting ``joints`` (their ``nominal`` angles); ValueError for a bad record."""
    onnx = _onnx()
    F, D = onnx.TensorProto.FLOAT, onnx.TensorProto.DOUBLE
    g = Graph(PREFIX)
    out, state = _layer(g, record, list(names), list(joints), list(nominal), control_period_s,
                        "observation", "action", "state_in")
    g.op("Cast", out, to=F, out="action_out")
    g.op("Identity", state, out="state_out")
    S, A = initial_state(record).shape[1], len(joints)
    io = _graph_io(onnx, [("observation", F, len(names)), ("action", F, A), ("state_in", D, S)],
                   [("action_out", F, A), ("state_out", D, S)])
    return _model(onnx, g.nodes, g.inits, "evomotion_capture_step", io, record)


def controller_model(spec: Any, params: np.ndarray, obs_mean: np.ndarray,
                     obs_std: np.ndarray, record: dict[str, Any], names: list[str],
                     joints: list[str], nominal: list[float], control_period_s: float) -> Any:
    """``controller.onnx``: the policy (:func:`evomotion.core.policies.onnx_graph.policy_model`)
    then the layer, one checked model: inputs ``observation``, ``state_in``; outputs
    ``action``, ``state_out``."""
    from evomotion.core.policies.onnx_graph import policy_model

    onnx = _onnx()
    F, D = onnx.TensorProto.FLOAT, onnx.TensorProto.DOUBLE
    policy = policy_model(spec, params, obs_mean, obs_std).graph
    nodes = list(policy.node)
    for n in nodes:  # the policy's output becomes the layer's input
        for i, o in enumerate(n.output):
            if o == "action":
                n.output[i] = n.name = PREFIX + "policy_action"
    g = Graph(PREFIX)
    out, state = _layer(g, record, list(names), list(joints), list(nominal), control_period_s,
                        "observation", PREFIX + "policy_action", "state_in")
    g.op("Cast", out, to=F, out="action")
    g.op("Identity", state, out="state_out")
    S, A = initial_state(record).shape[1], len(joints)
    io = _graph_io(onnx, [("observation", F, len(names)), ("state_in", D, S)],
                   [("action", F, A), ("state_out", D, S)])
    return _model(onnx, nodes + g.nodes, list(policy.initializer) + g.inits,
                  "evomotion_walk_controller", io, record)
