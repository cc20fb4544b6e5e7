"""Structured policies: a gait's phase generator (a Fourier tape) plus linear feedback.

Phase-driven joint trajectories are how sinusoidal/CPG gaits are evolved: Yu et al. 2014
("A survey on CPG-inspired control models and system implementation", ISRN Robotics), as
summarised in ``/work/shared/reference/walking.md`` [P5], set each joint to
``θ_j = θ_j⁰ + A_j sin(2πt/T + φ_j)`` and evolve ``T, A_j, φ_j, θ_j⁰``; walk engines close
the loop by adding sensor terms to the phase-driven targets (B-Human [B1]: the low-passed pitch
gyro x 0.05 added to the support ankle's pitch). Here both parts are one flat vector:

    tape(φ)_j = a_j0 + Σ_{k=1..H} (a_jk sin kφ + b_jk cos kφ)      (a Fourier series in φ;
                                                                   A sin(φ + φ_j) is H = 1)
    y = tape(φ) + K x
    action = clip(offset + scale * y, low, high)                   (no squashing, as linear)

``φ = 2πt / phase_period_s`` is read from the observation's RAW ``phase:sin``/``phase:cos``
columns (:mod:`evomotion.sim.observations`; ``phase_columns``), not normalised, and ``sin kφ``,
``cos kφ`` follow by the angle-addition recurrence ``sin (k+1)φ = sin kφ cos φ + cos kφ sin φ``,
``cos (k+1)φ = cos kφ cos φ − sin kφ sin φ`` (products and sums only, so numpy, ``policy.py``
and ONNX compute the same thing). ``x`` is the ARS V2 normalised observation (Mania et al.
2018, Algorithm 2 line 5, clipped to ``±clip_obs``) without the two phase columns; ``K`` the
``act_dim x (obs_dim − 2)`` feedback gains.

A command (``command_columns``: the observation's raw command values ``c_1..c_m``, e.g. a walk's
``vx, vy, ω``) modulates the tape: the features become ``g = (f, c_1 f, ..., c_m f)``, so
``tape(φ, c) = C_0 f(φ) + Σ_i c_i C_i f(φ)``, a gait whose every harmonic is an affine function
of the command (the step length, width and turn of a walk engine scale its foot trajectories by
the command; :func:`fit_tape` fits such a tape to an engine's trajectories at many commands).

Parameters (``n_params = a (1 + 2H)(1 + m) + a (o − 2)`` [``+ m (o − 2)``]): the tape first,
``C[a, (1 + 2H)(1 + m)]`` row-major with row ``j = (a_j0, a_j1, b_j1, ..., a_jH, b_jH)`` (the
weights of the features ``f(φ) = (1, sin φ, cos φ, ..., sin Hφ, cos Hφ)``; with a command, then
the same for ``c_1 f``, ..., ``c_m f``), then ``K`` row-major. Zero parameters give
the nominal pose ``offset``. :func:`fit_tape` fits ``C`` to an open-loop gait's keyframe
trajectory by least squares, :meth:`StructuredSpec.params_from_tape` makes it a start (K = 0).

**Command feedback** (``command_feedback``, with a command): the tape reads the command plus
a linear function of the same normalised observation, ``c' = c + G x`` (``G[m, o − 2]``, after
``K`` in the parameters), so a walk steps longer or wider the way its torso leans: a correction
of the step itself, which the phase-independent ``K x`` cannot express (capture-point step
adjustment, Pratt et al. 2006, as walk engines place the swing foot;
``benchmarks/command_feedback_probe.py`` measured a hand-set ``G`` on the IMU's gravity
direction). ``G = 0`` is the plain command-modulated tape.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from evomotion.core.policies.spec import Layer, PolicySpec

MAX_HARMONICS = 64


def phase_features(sin_phi: np.ndarray, cos_phi: np.ndarray, harmonics: int) -> np.ndarray:
    """``f[..., 1 + 2H] = (1, sin φ, cos φ, ..., sin Hφ, cos Hφ)`` by the angle-addition
    recurrence from ``sin φ``, ``cos φ`` (any shape, broadcast)."""
    s1, c1 = np.broadcast_arrays(np.asarray(sin_phi, np.float64), np.asarray(cos_phi, np.float64))
    out = [np.ones_like(s1)]
    s, c = s1, c1
    for k in range(1, harmonics + 1):
        out += [s, c]
        if k < harmonics:
            s, c = s * c1 + c * s1, c * c1 - s * s1
    return np.stack(out, axis=-1)


def _row_dot(W: np.ndarray, v: np.ndarray) -> np.ndarray:
    """``Σ_m W[..., a, m] v[..., m]`` summed in column order (not BLAS, whose order depends on
    shapes and threads): the same bits whether ``W`` is one policy's or one per row, in any
    memory layout (``policy.py`` sums alike, a loop over columns). The products in one call,
    then ``np.add.accumulate`` (a running sum, left to right by definition: the loop's
    additions in the loop's order) in another: never a loop over individuals or columns."""
    return np.add.accumulate(W * v[..., None, :], axis=-1)[..., -1]


@dataclass(frozen=True, eq=False)
class StructuredSpec(PolicySpec):
    """``clip(offset + scale * (tape(φ) + K x), low, high)`` (see the module doc)."""

    phase_columns: tuple[int, int] | None = None  # the (sin, cos) columns of the observation
    harmonics: int = 2  # H: sin/cos pairs of the tape per action
    command_columns: tuple[int, ...] = ()  # raw observation columns that modulate the tape
    command_feedback: bool = False  # the tape reads c + G x (module doc); needs a command

    kind: ClassVar[str] = "structured"
    squash_output: ClassVar[bool] = False

    def __post_init__(self) -> None:
        super().__post_init__()
        h = self.harmonics
        if isinstance(h, bool) or not isinstance(h, int | np.integer) or \
                not 0 <= h <= MAX_HARMONICS:
            raise ValueError(f"harmonics must be a whole number in 0..{MAX_HARMONICS}, got {h!r}")
        object.__setattr__(self, "harmonics", int(h))
        cols = self.phase_columns
        if cols is None:
            raise ValueError("the structured policy needs phase_columns: the observation's "
                             "phase:sin and phase:cos columns")
        try:
            pair: tuple = tuple(cols)
        except TypeError:
            pair = (cols,)
        if len(pair) != 2 or any(isinstance(c, bool) or not isinstance(c, int | np.integer)
                                 for c in pair):
            raise ValueError(f"phase_columns must be two column numbers (sin, cos), got {cols!r}")
        i, j = int(pair[0]), int(pair[1])
        if not (0 <= i < self.obs_dim and 0 <= j < self.obs_dim) or i == j:
            raise ValueError(f"phase_columns must be two different columns in 0..{self.obs_dim - 1}"
                             f", got {(i, j)}")
        object.__setattr__(self, "phase_columns", (i, j))
        raw = self.command_columns
        cmd: tuple = tuple(raw) if isinstance(raw, tuple | list | np.ndarray) else (raw,)
        if any(isinstance(c, bool) or not isinstance(c, int | np.integer)
               or not 0 <= int(c) < self.obs_dim or int(c) in (i, j) for c in cmd) or \
                len(set(int(c) for c in cmd)) != len(cmd):
            raise ValueError(f"command_columns must be different column numbers in "
                             f"0..{self.obs_dim - 1}, not the phase columns, got "
                             f"{self.command_columns!r}")
        object.__setattr__(self, "command_columns", tuple(int(c) for c in cmd))
        if not isinstance(self.command_feedback, bool | np.bool_) or \
                (self.command_feedback and not cmd):
            raise ValueError("command_feedback must be true or false, and true only with "
                             f"command_columns, got {self.command_feedback!r}")
        object.__setattr__(self, "command_feedback", bool(self.command_feedback))

    @property
    def n_features(self) -> int:
        """``(1 + 2H)(1 + m)``: the tape's features per action."""
        return (1 + 2 * self.harmonics) * (1 + len(self.command_columns))

    def features(self, obs: np.ndarray, command: np.ndarray | None = None) -> np.ndarray:
        """``g[n, (1 + 2H)(1 + m)] = (f, c_1 f, ..., c_m f)`` of raw observations (``command
        [n, m]``: the command values to use instead of the observation's)."""
        i, j = self.phase_columns  # type: ignore[misc]
        f = phase_features(obs[:, i], obs[:, j], self.harmonics)
        if not self.command_columns:
            return f
        c = obs[:, list(self.command_columns)] if command is None else command
        return np.concatenate([f] + [c[:, k, None] * f for k in range(c.shape[1])], axis=-1)

    @functools.cached_property
    def feedback_columns(self) -> np.ndarray:
        """The observation columns ``x`` is made of: all but the two phase columns, in order
        (worked out once per spec, read-only)."""
        cols = np.setdiff1d(np.arange(self.obs_dim), np.asarray(self.phase_columns))
        cols.setflags(write=False)
        return cols

    def layer_shapes(self) -> list[tuple[int, int]]:
        """The tape ``C[a, 1 + 2H]``, the gains ``K[a, o − 2]`` and, with command feedback,
        ``G[m, o − 2]`` (no biases)."""
        shapes = [(self.act_dim, self.n_features), (self.act_dim, self.obs_dim - 2)]
        if self.command_feedback:
            shapes.append((len(self.command_columns), self.obs_dim - 2))
        return shapes

    def layer_has_bias(self, i: int) -> bool:
        return False

    def act(self, params: np.ndarray, obs: np.ndarray, mean: np.ndarray, std: np.ndarray
            ) -> np.ndarray:
        """``actions[n, a]``: each row's tape at its raw phase plus its gains on its normalised
        observation (``mean``/``std``: ``(o,)`` or one per row ``(n, o)``)."""
        obs = self._check_act(params, obs, mean, std)
        layers = self.unflatten(params)
        (C, _), (K, _) = layers[:2]
        x = self.normalise(obs, mean, std)[:, self.feedback_columns] if K.shape[-1] else None
        command = None
        if self.command_feedback and x is not None:  # c' = c + G x
            command = obs[:, list(self.command_columns)] + _row_dot(layers[2][0], x)
        y = _row_dot(C, self.features(obs, command))
        if x is not None:
            y = y + _row_dot(K, x)
        return np.clip(self.offset + self.scale * y, self.low, self.high)

    def params_from_tape(self, coeffs: np.ndarray) -> np.ndarray:
        """The flat parameters of the tape ``coeffs[a, 1 + 2H]`` with zero feedback gains."""
        C = np.asarray(coeffs, dtype=np.float64)
        if C.shape != (self.act_dim, self.n_features) or not np.isfinite(C).all():
            raise ValueError(f"tape coefficients must be finite, of shape "
                             f"({self.act_dim}, {self.n_features}), got {C.shape}")
        layers: list[Layer] = [(C, None), (np.zeros((self.act_dim, self.obs_dim - 2)), None)]
        if self.command_feedback:
            layers.append((np.zeros((len(self.command_columns), self.obs_dim - 2)), None))
        return self.flatten(layers)


def fit_tape(times_s: np.ndarray, targets: np.ndarray, period_s: float, harmonics: int,
             commands: np.ndarray | None = None) -> np.ndarray:
    """Least-squares tape ``coeffs[a, 1 + 2H]`` (rows as in the module doc) through the samples
    ``targets[T, a]`` at ``times_s[T]``, with ``φ = 2π t / period_s``. Fit the policy's output
    ``y``: for a pose trajectory ``q`` that is ``(q − offset) / scale``. With
    ``commands[T, m]`` (the command at each sample) the tape is command-modulated:
    ``coeffs[a, (1 + 2H)(1 + m)]``."""
    t = np.asarray(times_s, dtype=np.float64)
    q = np.asarray(targets, dtype=np.float64)
    if isinstance(harmonics, bool) or not isinstance(harmonics, int | np.integer) or \
            not 0 <= harmonics <= MAX_HARMONICS:
        raise ValueError(f"harmonics must be a whole number in 0..{MAX_HARMONICS}, "
                         f"got {harmonics!r}")
    if not (math.isfinite(period_s) and period_s > 0):
        raise ValueError(f"period_s must be finite and > 0, got {period_s!r}")
    if t.ndim != 1 or q.ndim != 2 or q.shape[0] != t.size:
        raise ValueError(f"times_s[T] and targets[T, a] expected, got shapes {t.shape}, "
                         f"{q.shape}")
    if not (np.isfinite(t).all() and np.isfinite(q).all()):
        raise ValueError("times_s and targets must be finite")
    phi = 2.0 * np.pi * t / float(period_s)
    F = phase_features(np.sin(phi), np.cos(phi), int(harmonics))
    if commands is not None:
        c = np.asarray(commands, dtype=np.float64)
        if c.ndim != 2 or c.shape[0] != t.size or not np.isfinite(c).all():
            raise ValueError(f"commands must be finite, of shape ({t.size}, m), got {c.shape}")
        F = np.concatenate([F] + [c[:, k, None] * F for k in range(c.shape[1])], axis=-1)
    if np.linalg.matrix_rank(F) < F.shape[1]:
        raise ValueError(f"{t.size} samples do not determine {F.shape[1]} tape coefficients "
                         f"(need at least {F.shape[1]} distinct phases)")
    coeffs, *_ = np.linalg.lstsq(F, q, rcond=None)
    return np.ascontiguousarray(coeffs.T)
