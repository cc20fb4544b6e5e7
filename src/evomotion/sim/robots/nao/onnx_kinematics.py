"""Float64 ONNX expressions for :mod:`.capture_step_onnx`: a small graph builder, the math the
capture step needs in double precision, and the NAO's closed-form leg kinematics as subgraphs.

A value (:class:`V`) is a tensor's name or a numpy constant; arithmetic on values emits ONNX
nodes (opset 17) into a :class:`Graph`, folding constants while building and skipping the
structural zeros and ones of rotation matrices (``0·x``, ``1·x``, ``x + 0``), so the nodes
follow :mod:`.leg_ik`'s and the walk engine's numpy expressions in the same order of
operations. Everything is float64: onnxruntime's CPU provider (1.32) runs Sin, Cos, Sqrt,
Floor, Round, Mod, Max, Min, Where and the arithmetic in float64, but Atan, Acos, Asin and Tan
in float32 only. :func:`atan2` therefore takes a float32 ``Atan`` as its first guess ``θ₀``
(the quadrant from the signs, |y| > |x| from the ratio) and corrects it once in float64,

    θ = θ₀ + e,   e = (y cos θ₀ − x sin θ₀) / (x cos θ₀ + y sin θ₀) = tan(θ − θ₀)

(taking ``e`` for ``atan e`` errs by about ``e³/3``: 3e-22 at ``|θ − θ₀| ≈ 1e-7``, a float32
``Atan``'s error); ``acos z = atan2(√((1−z)(1+z)), z)``. There is no Atan2 in ONNX. Values
are tensors ``[batch, foot (1 or 2), variant (1 or 2)]``; per-foot constants have shape
``[2, 1]`` (left, right).

Leg kinematics (:mod:`.leg_ik`: Graf, Härtl, Röfer, Laue 2009, the NAO's published geometry):
:func:`ankle` is the closed-form forward chain, :func:`leg_ik` the inverse, both per foot.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

Number = Any  # V, float or a numpy array
_FOLD: dict[str, Callable[..., Any]] = {
    "Add": np.add, "Sub": np.subtract, "Mul": np.multiply, "Div": np.divide,
    "Less": np.less, "Greater": np.greater, "Equal": np.equal, "And": np.logical_and,
    "GreaterOrEqual": np.greater_equal, "LessOrEqual": np.less_equal,
    "Or": np.logical_or, "Max": np.maximum, "Min": np.minimum, "Sin": np.sin, "Cos": np.cos,
    "Sqrt": np.sqrt, "Neg": np.negative, "Abs": np.abs, "Floor": np.floor, "Round": np.round,
    "IsNaN": np.isnan, "Not": np.logical_not}


class Graph:
    """Nodes and initializers, their names under ``prefix``."""

    def __init__(self, prefix: str) -> None:
        self.prefix = prefix
        self.nodes: list[Any] = []
        self.inits: list[Any] = []
        self._consts: dict[tuple, str] = {}

    def const(self, value: Any, name: str | None = None) -> str:
        """An initializer (float64 unless int64 or bool), shared between equal values."""
        from onnx import numpy_helper

        a = np.asarray(value)
        a = a if a.dtype in (np.int64, np.bool_) else a.astype(np.float64)
        key = (a.dtype.str, a.shape, a.tobytes())
        if name is None and key in self._consts:
            return self._consts[key]
        out = self.prefix + (name or f"const{len(self.inits)}")
        self.inits.append(numpy_helper.from_array(a, out))
        if name is None:
            self._consts[key] = out
        return out

    def op(self, op: str, *inputs: str, out: str | None = None, **attrs: Any) -> str:
        from onnx import helper

        name = out or f"{self.prefix}{op}_{len(self.nodes)}"
        self.nodes.append(helper.make_node(op, list(inputs), [name], name=name, **attrs))
        return name

    def v(self, x: Number) -> V:
        if isinstance(x, V):
            return x
        a = np.asarray(x)
        return V(self, value=a if a.dtype == np.bool_ else a.astype(np.float64))

    def tensor(self, name: str) -> V:
        return V(self, name=name)

    def named(self, value: Any, name: str) -> V:
        """A constant kept as its own initializer ``name`` (not folded): a setting to find."""
        return V(self, name=self.const(value, name))


class V:
    """A tensor (``name``) or a constant (``value``) of a :class:`Graph`."""

    __slots__ = ("g", "name", "value")
    __array_ufunc__ = None  # numpy array (op) value: the value's reflected operator

    def __init__(self, g: Graph, name: str | None = None, value: Any = None) -> None:
        self.g, self.name, self.value = g, name, value

    @property
    def ref(self) -> str:
        return self.name if self.name is not None else self.g.const(self.value)

    def _is(self, k: float) -> bool:
        return self.value is not None and bool(np.all(self.value == k))

    def __add__(self, o: Number) -> V:
        return apply("Add", self, o)

    def __radd__(self, o: Number) -> V:
        return apply("Add", o, self)

    def __sub__(self, o: Number) -> V:
        return apply("Sub", self, o)

    def __rsub__(self, o: Number) -> V:
        return apply("Sub", o, self)

    def __mul__(self, o: Number) -> V:
        return apply("Mul", self, o)

    def __rmul__(self, o: Number) -> V:
        return apply("Mul", o, self)

    def __truediv__(self, o: Number) -> V:
        return apply("Div", self, o)

    def __rtruediv__(self, o: Number) -> V:
        return apply("Div", o, self)

    def __neg__(self) -> V:
        return apply("Neg", self)


def _graph(*xs: Number) -> Graph:
    return next(x.g for x in xs if isinstance(x, V))


def apply(op: str, *xs: Number, **attrs: Any) -> V:
    """``op`` on values (folded when all are constants; ``0·x`` → 0, ``1·x``, ``x ± 0``,
    ``x / 1`` → ``x``, ``−1·x``, ``0 − x`` → ``−x``: the rotations' structural entries)."""
    g = _graph(*xs)
    vs = [g.v(x) for x in xs]
    if all(v.value is not None for v in vs) and op in _FOLD and not attrs:
        return V(g, value=np.asarray(_FOLD[op](*(v.value for v in vs))))
    if len(vs) == 2:
        a, b = vs
        if op == "Add" and (a._is(0) or b._is(0)):
            return b if a._is(0) else a
        if op == "Sub" and b._is(0):
            return a
        if op == "Sub" and a._is(0):
            return -b
        if op == "Mul" and (a._is(0) or b._is(0)):
            return g.v(0.0)
        if op in ("Mul", "Div") and b._is(1):
            return a
        if op == "Mul" and a._is(1):
            return b
        if op == "Mul" and (a._is(-1) or b._is(-1)):
            return -(b if a._is(-1) else a)
    return V(g, name=g.op(op, *(v.ref for v in vs), **attrs))


def where(c: Number, a: Number, b: Number) -> V:
    return apply("Where", c, a, b)


def lt(a: Number, b: Number) -> V:
    return apply("Less", a, b)


def gt(a: Number, b: Number) -> V:
    return apply("Greater", a, b)


def eq(a: Number, b: Number) -> V:
    return apply("Equal", a, b)


def ge(a: Number, b: Number) -> V:
    return apply("GreaterOrEqual", a, b)


def clip(x: Number, lo: Number, hi: Number) -> V:
    """``np.clip`` (NaN stays NaN: onnxruntime's Max and Min propagate it)."""
    return apply("Min", apply("Max", x, lo), hi)


def finite(x: V) -> V:
    """``x`` is finite: ``x − x == 0`` (NaN − NaN and ∞ − ∞ are NaN)."""
    return eq(x - x, 0.0)


def to_double(x: V) -> V:
    from onnx import TensorProto

    return apply("Cast", x, to=TensorProto.DOUBLE)


def mod(x: Number, m: float) -> V:
    """numpy's ``x % m`` for ``m > 0`` (C's fmod, then shifted into [0, m))."""
    r = apply("Mod", x, m, fmod=1)
    return where(lt(r, 0.0), r + m, r)


def atan2(y: Number, x: Number) -> V:
    """``np.arctan2`` in float64 for finite inputs (module doc); 0 at (0, 0), NaN for a NaN
    input; unlike numpy, the sign of a zero is not read (0 at (0, −0.0), π at (−0.0, −1)) and
    infinite inputs give NaN: neither occurs for a gait clock's sin and cos."""
    from onnx import TensorProto

    g = _graph(y, x)
    y, x = g.v(y), g.v(x)
    ay, ax = apply("Abs", y), apply("Abs", x)
    lo, hi = apply("Min", ay, ax), apply("Max", ay, ax)
    ratio = apply("Cast", lo / where(eq(hi, 0.0), 1.0, hi), to=TensorProto.FLOAT)
    a = to_double(apply("Atan", ratio))
    a = where(gt(ay, ax), math.pi / 2 - a, a)
    a = where(lt(x, 0.0), math.pi - a, a)
    t0 = where(lt(y, 0.0), -a, a)
    c, s = apply("Cos", t0), apply("Sin", t0)
    e = (y * c - x * s) / (x * c + y * s)
    return t0 + where(finite(e), e, 0.0)


def acos(z: Number) -> V:
    """``np.arccos`` of ``z ∈ [-1, 1]`` in float64."""
    return atan2(apply("Sqrt", (1.0 - z) * (1.0 + z)), z)


Matrix = list[list[Number]]


def rotation(a: Number, axis: int) -> Matrix:
    """:func:`.leg_ik.rot_x` (axis 0), ``rot_y`` (1), ``rot_z`` (2) of an angle value."""
    g = _graph(a) if isinstance(a, V) else None
    c, s = (apply("Cos", a), apply("Sin", a)) if g else (np.cos(a), np.sin(a))
    i, j = (axis + 1) % 3, (axis + 2) % 3
    R: Matrix = [[0.0] * 3 for _ in range(3)]
    R[axis][axis], R[i][i], R[i][j], R[j][i], R[j][j] = 1.0, c, -s, s, c
    return R


def _sum(terms: Sequence[Number]) -> Number:
    out = terms[0]
    for t in terms[1:]:
        out = out + t
    return out


def _mul(a: Number, b: Number) -> Number:
    if isinstance(a, V) or isinstance(b, V):
        return apply("Mul", a, b)
    return np.multiply(a, b)


def matmul(a: Matrix, b: Matrix) -> Matrix:
    return [[_sum([_mul(a[i][k], b[k][j]) for k in range(3)]) for j in range(3)]
            for i in range(3)]


def matvec(a: Matrix, v: Sequence[Number]) -> list[Number]:
    return [_sum([_mul(a[i][k], v[k]) for k in range(3)]) for i in range(3)]


def transpose(a: Matrix) -> Matrix:
    return [[a[j][i] for j in range(3)] for i in range(3)]


class Leg:
    """The NAO's legs (``geometry``: the record's ``hip_offset_y_m``, ``hip_offset_z_m``,
    ``thigh_m``, ``tibia_m``), both feet at once: side ``s = [+1, −1]`` per foot."""

    def __init__(self, geometry: dict[str, float]) -> None:
        self.hip_y = float(geometry["hip_offset_y_m"])
        self.hip_z = float(geometry["hip_offset_z_m"])
        self.thigh, self.tibia = float(geometry["thigh_m"]), float(geometry["tibia_m"])
        self.s = np.array([[1.0], [-1.0]])
        self.hip = [0.0, np.array([[self.hip_y], [-self.hip_y]]), -self.hip_z]

    def ankle(self, q: Sequence[Number]) -> list[Number]:
        """:func:`.leg_ik.ankle_position` of the angles ``q[0..3]`` (hip yaw-pitch, roll,
        pitch, knee; the ankle's own two do not move it)."""
        tilt, untilt = rotation(-self.s * np.pi / 4, 0), rotation(self.s * np.pi / 4, 0)
        r_hip = matmul(matmul(matmul(matmul(tilt, rotation(q[0], 1)), untilt),
                              rotation(q[1], 0)), rotation(q[2], 1))
        knee = [self.hip[i] + self.thigh * -r_hip[i][2] for i in range(3)]
        r_knee = matmul(r_hip, rotation(q[3], 1))
        return [knee[i] + self.tibia * -r_knee[i][2] for i in range(3)]

    def ik(self, p: Sequence[Number], R: Matrix) -> list[V]:
        """:func:`.leg_ik.leg_ik`: the six angles putting the ankle at ``p`` with the foot's
        rotation ``R``."""
        s, T, L = self.s, self.thigh, self.tibia
        v = matvec(transpose(R), [self.hip[i] - p[i] for i in range(3)])
        q5 = atan2(v[1], v[2])
        q5 = where(gt(q5, np.pi / 2), q5 - np.pi,
                   where(apply("LessOrEqual", q5, -np.pi / 2), q5 + np.pi, q5))
        d2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
        q3 = acos(clip((d2 - T**2 - L**2) / (2 * T * L), -1.0, 1.0))
        u = matvec(rotation(q5, 0), v)
        w_x, w_z = -T * apply("Sin", q3), L + T * apply("Cos", q3)
        q4 = atan2(w_x, w_z) - atan2(u[0], u[2])
        q4 = mod(q4 + np.pi, 2 * np.pi) - np.pi
        M = matmul(matmul(matmul(rotation(s * np.pi / 4, 0), R), rotation(-q5, 0)),
                   rotation(-(q3 + q4), 1))
        b = atan2(s * apply("Sqrt", M[1][0] * M[1][0] + M[1][2] * M[1][2]), M[1][1])
        q0 = atan2(s * M[0][1], s * M[2][1])
        q2 = atan2(s * M[1][0], -s * M[1][2])
        return [q0, b - s * np.pi / 4, q2, q3, q4, q5]
