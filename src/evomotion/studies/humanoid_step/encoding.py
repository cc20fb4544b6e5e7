"""Servo trajectories from genomes: the paper's piecewise-linear knots and its alternatives.

Paper 000 (Chikishev & Sizikov 2009, section 2.2 and ``Main.createIndividual``): the step time
``T`` is split into ``K`` equal intervals; the value of each of the 10 leg servos at every
interval boundary is a gene, the first and last boundary are pinned to the initial pose, and
values in between are linear in time (``SplineTwo``: ``y = a x + b``). Section 3.2 names the
alternatives used here: a cubic spline through the same knots (clamped: zero velocity at both
pinned ends) and a harmonic function ``a sin(w t) + b cos(w t) + c`` per servo.

Linear/spline genome (servo-major): ``genes[servo * (K - 1) + k]`` = value (rad) of ``servo``
at ``t = (k + 1) T / K``. Harmonic genome: ``(a, b, c)`` per servo then one shared ``w``
(rad/s); the servo moves as ``q0 + s(t) (a sin wt + b cos wt + c)`` with the window
``s(t) = sin^2(pi t / T)``, so that it too starts and ends in the initial pose.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.interpolate import CubicSpline

from evomotion.core.problem import GenomeSpec

ENCODINGS = ("linear", "spline", "harmonic")


@dataclass(frozen=True)
class ServoEncoding:
    """Maps genomes to servo targets ``[pop, len(t), n_servo]`` for servos starting at ``q0``.

    ``lower``/``upper`` are the servo bounds (rad); ``motion_s`` is the step time ``T``.
    """

    kind: str
    q0: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    intervals: int
    motion_s: float
    omega_max: float = 4.0 * np.pi  # rad/s, harmonic only

    def __post_init__(self) -> None:
        if self.kind not in ENCODINGS:
            from evomotion.errors import InputError

            raise InputError(f"unknown encoding {self.kind!r}; available: {', '.join(ENCODINGS)}")
        if self.intervals < 2:
            raise ValueError(f"intervals must be >= 2, got {self.intervals}")

    @property
    def n_servo(self) -> int:
        return int(self.q0.size)

    @property
    def knot_times(self) -> np.ndarray:
        """Interval boundaries ``t_k = k T / K``, k = 0..K (s)."""
        return np.linspace(0.0, self.motion_s, self.intervals + 1)

    def genome(self, names: tuple[str, ...]) -> GenomeSpec:
        n = self.n_servo
        if self.kind == "harmonic":
            amp = 0.5 * (self.upper - self.lower)
            lo = np.column_stack([-amp, -amp, self.lower - self.q0]).ravel()
            hi = np.column_stack([amp, amp, self.upper - self.q0]).ravel()
            lo = np.append(lo, np.pi / self.motion_s)
            hi = np.append(hi, self.omega_max)
            slices = {name: slice(3 * i, 3 * i + 3) for i, name in enumerate(names)}
            slices["omega"] = slice(3 * n, 3 * n + 1)
            return GenomeSpec(lo, hi, slices)
        m = self.intervals - 1
        lo, hi = np.repeat(self.lower, m), np.repeat(self.upper, m)
        slices = {name: slice(i * m, (i + 1) * m) for i, name in enumerate(names)}
        return GenomeSpec(lo, hi, slices)

    def knots(self, genomes: np.ndarray) -> np.ndarray:
        """Linear/spline: ``[pop, K + 1, n_servo]`` knot values including the pinned ends."""
        pop = genomes.shape[0]
        inner = genomes.reshape(pop, self.n_servo, self.intervals - 1).transpose(0, 2, 1)
        ends = np.broadcast_to(self.q0, (pop, 1, self.n_servo))
        return np.concatenate([ends, inner, ends], axis=1)

    def targets(self, genomes: np.ndarray, t: np.ndarray) -> np.ndarray:
        """Servo targets ``[pop, len(t), n_servo]`` at times ``t`` (s); after ``T`` the
        initial pose is held. Values are clipped into the servo bounds."""
        genomes = np.atleast_2d(np.asarray(genomes, dtype=float))
        t = np.asarray(t, dtype=float)
        tc = np.clip(t, 0.0, self.motion_s)
        if self.kind == "harmonic":
            n = self.n_servo
            abc = genomes[:, : 3 * n].reshape(-1, n, 3)
            w = genomes[:, 3 * n][:, None, None]
            wt = w * tc[None, :, None]
            a, b, c = (abc[:, None, :, i] for i in range(3))
            wave = a * np.sin(wt) + b * np.cos(wt) + c
            window = np.sin(np.pi * tc / self.motion_s)[None, :, None] ** 2
            out = self.q0 + window * wave
        elif self.kind == "linear":
            knots = self.knots(genomes)
            kt = self.knot_times
            idx = np.clip(np.searchsorted(kt, tc, side="right") - 1, 0, self.intervals - 1)
            frac = ((tc - kt[idx]) / (kt[idx + 1] - kt[idx]))[None, :, None]
            out = knots[:, idx] * (1.0 - frac) + knots[:, idx + 1] * frac
        else:
            spline = CubicSpline(self.knot_times, self.knots(genomes), axis=1, bc_type="clamped")
            out = spline(tc)
        return np.clip(out, self.lower, self.upper)
