"""Balance feedback during the kick (issue 34: "the kick evolved with the walk's balance
feedback"): the support leg's ankle reads the torso's gyro.

Every ``control_period_s`` of the rollout (the settle before the kick, the kick and the
ball's roll after it) the support ankle's pitch and roll targets move by

    Δq_pitch = k_pitch · ω_y,    Δq_roll = k_roll · ω_x                       (1)

with ``ω`` the torso's angular velocity in its own frame (the NAO's gyro: rad/s) read at the
start of the period and ``k`` in s (rad per rad/s): the walk engines' balance term (B-Human
adds the low-passed pitch gyro x 0.05 to the support ankle's pitch, ``walking.md`` §1; its
kick engine balances with a gyro controller too, ``kick-and-rendering.md``). The targets
reach the servos after each world's latency (:func:`evomotion.sim.worlds.simulate_worlds`'s
``feedback``). The support leg is the left one for a right-foot kick and the right one for a
mirrored, left-foot kick; the NAO's ankle axes are the same on both sides, so the gains are.
``balance_gains = (0, 0)`` is the open-loop kick, simulated as before.
"""

from __future__ import annotations

import numpy as np

from evomotion.errors import InputError
from evomotion.sim.control_period import whole_steps
from evomotion.sim.state import state_qvel

#: the kick scene's free joint (the torso) and the support ankles' actuators per side
ROOT = "root"
ANKLES = {"left": ("LAnklePitch", "LAnkleRoll"), "right": ("RAnklePitch", "RAnkleRoll")}
MAX_GAIN_S = 1.0


def control_steps(model, period_s: float) -> int:
    """Physics steps per control period; one line unless ``period_s`` is a whole number of
    the scene's steps."""
    dt = float(model.opt.timestep)
    k = whole_steps(period_s, dt)
    if k is None:
        raise InputError(f"problem.control_period_s: {period_s} s is not a whole number of "
                         f"the kick scene's {dt} s physics steps")
    return k


class BalanceFeedback:
    """Equation (1) for a batch of kicks: ``left[i]`` true where kick ``i`` is the mirrored,
    left-foot one (its support leg the right)."""

    def __init__(self, model, gains: tuple[float, float], left: np.ndarray) -> None:
        names = {model.actuator(i).name: i for i in range(model.nu)}
        missing = [n for side in ANKLES.values() for n in side if n not in names]
        if missing:
            raise InputError(f"problem.balance_gains: the robot has no {', '.join(missing)} "
                             "actuator (the balance feedback drives the NAO's ankles)")
        self.model, self.nu = model, model.nu
        self.k_pitch, self.k_roll = (float(g) for g in gains)
        left = np.asarray(left, dtype=bool)
        pick = {s: [names[n] for n in ANKLES[s]] for s in ANKLES}
        # the support ankle: the left one for a right-foot kick
        self.pitch = np.where(left, pick["right"][0], pick["left"][0])
        self.roll = np.where(left, pick["right"][1], pick["left"][1])

    def __call__(self, rows: np.ndarray, start: int, states: np.ndarray) -> np.ndarray:
        """The target offsets ``[len(rows), nu]`` (rad) from ``states`` of kicks ``rows``."""
        omega = state_qvel(self.model, states, ROOT, 6)[:, 3:6]  # body frame (MuJoCo's free
        out = np.zeros((len(rows), self.nu))                     # joint angular velocity)
        i = np.arange(len(rows))
        out[i, self.pitch[rows]] = self.k_pitch * omega[:, 1]
        out[i, self.roll[rows]] = self.k_roll * omega[:, 0]
        return out
