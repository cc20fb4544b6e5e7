"""A joint-space gait for any robot with a ``[gait]`` spec: oscillators on role channels.

The NAO walk (:mod:`.gait`) places the feet in Cartesian space through the NAO's leg IK; a
robot known only by its MJCF and spec (:mod:`evomotion.sim.robots`) gets the other classic
open-loop parameterisation instead, a central-pattern-generator-like set of phase-locked
sinusoids on its leg joints (Ijspeert, "Central pattern generators for locomotion control",
Neural Networks 21, 2008; as tuned by evolution on biped and quadruped gaits). Every gene is an
amplitude, a phase, a period or an offset with a physical meaning, and every genome decodes to
targets inside the actuators' ranges.

Biped (legs left, right in antiphase; ``theta = 2 pi t / T + pi [right]``), per leg and role,
added to the robot's initial pose with the role's sign (spec ``[gait]``):

- ``hip_pitch = crouch/2 + lean + e hip_amp (1 + s trim) sin theta`` (s = +1 left, -1 right);
- ``knee = crouch + e knee_amp max(0, sin(theta + knee_phase))`` (flexes in swing only);
- ``ankle_pitch = crouch/2 + e ankle_amp sin(theta + ankle_phase)``;
- ``hip_roll = e roll_amp sin(theta_left + roll_phase)``, ``ankle_roll = -hip_roll`` (the body
  sways over the stance foot; both legs the same way).

Quadruped (trot: front left and hind right in phase, the other diagonal in antiphase):
``swing = e swing_amp (1 + s trim) sin theta``, ``lift = lift_offset + e lift_amp max(0,
sin(theta + lift_phase))``, ``extend = e extend_amp sin(theta + extend_phase)``.

The knee (biped) and lift (quadruped) amplitudes are at least 0.15 rad / 0.1: every gait
lifts its feet (without that bound evolution finds shuffles that slide the soles along the
floor). ``e`` (amplitude) rises from 0 to 1 over the first ``RAMP_CYCLES`` cycles and falls
back to 0 over one cycle after ``walk_s`` of full amplitude; the offsets (crouch, lean, lift)
ease in over ``OFFSET_RAMP_S`` and are held to the end. Units: rad, s (tendon channels: the
actuator's units).
"""

from __future__ import annotations

import math

import numpy as np

RAMP_CYCLES = 2
OFFSET_RAMP_S = 0.5
PI = math.pi

GENES = {
    "biped": (("period_s", 0.3, 1.6, 0.8), ("hip_amp_rad", 0.0, 0.6, 0.15),
              ("knee_amp_rad", 0.15, 1.0, 0.3), ("knee_phase_rad", -PI, PI, 1.2),
              ("ankle_amp_rad", 0.0, 0.6, 0.1), ("ankle_phase_rad", -PI, PI, 0.0),
              ("roll_amp_rad", 0.0, 0.25, 0.04), ("roll_phase_rad", -PI, PI, 0.0),
              ("crouch_rad", 0.0, 0.8, 0.2), ("lean_rad", -0.3, 0.3, 0.0),
              ("trim", -0.3, 0.3, 0.0)),
    "quadruped": (("period_s", 0.2, 1.2, 0.5), ("swing_amp", 0.0, 0.6, 0.2),
                  ("lift_amp", 0.1, 1.0, 0.3), ("lift_phase_rad", -PI, PI, 1.2),
                  ("lift_offset", -0.5, 0.5, 0.0), ("extend_amp", 0.0, 0.8, 0.0),
                  ("extend_phase_rad", -PI, PI, 0.0), ("trim", -0.3, 0.3, 0.0)),
}
#: leg phase offsets (rad) and sides (+1 left, -1 right) per kind
LEG_PHASE = {"biped": np.array([0.0, PI]), "quadruped": np.array([0.0, PI, PI, 0.0])}
LEG_SIDE = {"biped": np.array([1.0, -1.0]), "quadruped": np.array([1.0, -1.0, 1.0, -1.0])}


def gene_table(kind: str) -> tuple[tuple[str, ...], np.ndarray, np.ndarray, np.ndarray]:
    """(names, lower, upper, default) of a gait kind's genes."""
    rows = GENES[kind]
    return (tuple(r[0] for r in rows), np.array([r[1] for r in rows]),
            np.array([r[2] for r in rows]), np.array([r[3] for r in rows]))


def envelopes(t: np.ndarray, period_s: np.ndarray, walk_s: float) -> tuple[np.ndarray, ...]:
    """(amplitude envelope ``[P, T]``, offset envelope ``[T]``) at times ``t[T]``."""
    ramp = RAMP_CYCLES * period_s[:, None]
    walk_end = walk_s + ramp  # the ramp-up comes before walk_s of full amplitude
    up = np.clip(t[None] / ramp, 0.0, 1.0)
    down = np.clip((walk_end + period_s[:, None] - t[None]) / period_s[:, None], 0.0, 1.0)
    amp = _smooth(np.minimum(up, down))
    return amp, _smooth(np.clip(t / OFFSET_RAMP_S, 0.0, 1.0))


def _smooth(x: np.ndarray) -> np.ndarray:
    return x * x * (3.0 - 2.0 * x)


def walk_seconds(period_s: np.ndarray, walk_s: float) -> np.ndarray:
    """Seconds from the start to the end of the ramp-down (``[P]``)."""
    return (RAMP_CYCLES + 1) * period_s + walk_s


def targets(genomes: np.ndarray, kind: str, roles: dict, base: np.ndarray,
            lo: np.ndarray, hi: np.ndarray, t: np.ndarray, walk_s: float) -> np.ndarray:
    """Actuator targets ``[P, T, nu]`` of ``genomes[P, G]`` at times ``t[T]``: ``base`` (the
    initial pose) plus each role's signed value (``roles``: role -> ((column, sign) per
    leg)), clipped to the actuator ranges ``lo``/``hi``."""
    names = gene_table(kind)[0]
    g = {n: genomes[:, i][:, None] for i, n in enumerate(names)}  # [P, 1]
    amp, off = envelopes(t, genomes[:, 0], walk_s)
    out = np.broadcast_to(base, (len(genomes), t.size, base.size)).copy()
    for leg, (phase, side) in enumerate(zip(LEG_PHASE[kind], LEG_SIDE[kind], strict=True)):
        theta = 2 * PI * t[None] / g["period_s"] + phase  # [P, T]
        for role, value in _roles(kind, g, amp, off, theta, side, t).items():
            if role in roles:
                col, sign = roles[role][leg]
                out[:, :, col] += sign * value
    return np.clip(out, lo, hi)


def _roles(kind: str, g: dict, amp, off, theta, side: float, t) -> dict[str, np.ndarray]:
    if kind == "biped":
        sway = amp * g["roll_amp_rad"] * np.sin(2 * PI * t[None] / g["period_s"]
                                                 + g["roll_phase_rad"])
        crouch = off * g["crouch_rad"]
        return {
            "hip_pitch": crouch / 2 + off * g["lean_rad"]
            + amp * g["hip_amp_rad"] * (1 + side * g["trim"]) * np.sin(theta),
            "knee": crouch + amp * g["knee_amp_rad"]
            * np.maximum(0.0, np.sin(theta + g["knee_phase_rad"])),
            "ankle_pitch": crouch / 2 + amp * g["ankle_amp_rad"]
            * np.sin(theta + g["ankle_phase_rad"]),
            "hip_roll": sway, "ankle_roll": -sway,
        }
    return {
        "swing": amp * g["swing_amp"] * (1 + side * g["trim"]) * np.sin(theta),
        "lift": off * g["lift_offset"] + amp * g["lift_amp"]
        * np.maximum(0.0, np.sin(theta + g["lift_phase_rad"])),
        "extend": amp * g["extend_amp"] * np.sin(theta + g["extend_phase_rad"]),
    }
