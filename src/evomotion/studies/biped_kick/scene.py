"""The kick scene: the NAO H25 model plus a RoboCup SPL ball on a calibrated carpet.

Ball: 100 mm diameter, 45 g (the issue's figures for the SPL ball; the SPL rule book specifies a
black-and-white foam ball of 100 mm diameter — its mass is taken from the issue, not re-verified),
a solid sphere (foam) with ``condim = 6`` so that MuJoCo applies torsional and rolling friction.

Carpet: rolling friction ``rolling_m`` (a length: rolling torque = rolling_m * normal force);
for a solid ball the rolling deceleration is ``a = rolling_m g / (1.4 r)``. The default
:data:`CARPET_ROLLING_M` is **calibrated** so that the ball's deceleration measured in this
scene (:func:`measured_deceleration`) is :data:`CARPET_DECELERATION_M_S2` = 0.35 m/s^2, the
value B-Human's code release configures for the SPL ball on an SPL field
(``Config/Locations/Default/ballSpecification.cfg`` of bhuman/BHumanCodeRelease: ``friction =
-0.35 m/(s*s)``, used by its ball model to predict where a rolling ball stops; a team's fitted
figure, not a laboratory measurement). Issues 15-33 assumed 0.005 m (0.70 m/s^2, twice as
much), so their kick distances were about half of today's for the same ball speed.

The scene is built with :func:`evomotion.sim.robots.nao.scene.scene_xml` (without editing the NAO
files): the ball body and the sole sensors :data:`evomotion.sim.robots.nao.scene.SOLE_SENSORS`.
"""

from __future__ import annotations

from functools import lru_cache

import mujoco
import numpy as np

from evomotion.sim.robots import nao
from evomotion.sim.robots.nao.scene import SOLE_SENSORS, scene_xml, sensor_slices

__all__ = ["BALL_MASS_KG", "BALL_RADIUS_M", "CARPET_DECELERATION_M_S2", "CARPET_ROLLING_M",
           "calibrated_rolling_m", "SOLE_HALF_M", "ball_qpos_index", "ball_qvel_index",
           "default_ball_xy", "initial_scene_state", "kick_scene_xml", "load_scene",
           "measured_deceleration", "rolling_deceleration", "sensor_slices"]

BALL_RADIUS_M = 0.05
BALL_MASS_KG = 0.045
SOLE_HALF_M = nao.SOLE_HALF_M
BALL_JOINT = "ball"
#: the SPL ball's rolling deceleration on SPL carpet (m/s^2; B-Human, see the module doc)
CARPET_DECELERATION_M_S2 = 0.35
#: the rolling friction (m) whose measured deceleration in this scene is
#: :data:`CARPET_DECELERATION_M_S2` (:func:`calibrated_rolling_m` gives 0.002497; rounded,
#: 0.3504 m/s^2; a test keeps the two within 1 %)
CARPET_ROLLING_M = 0.0025

_BALL = """<body name="ball" pos="{x} {y} {z}"><freejoint name="ball"/>
<geom name="ball" type="sphere" size="{r}" mass="{m}" condim="6" contype="2" conaffinity="2"
 friction="0.7 0.005 {roll}" rgba="0.95 0.95 0.95 1"/></body>
"""


def kick_scene_xml(ball_xy: tuple[float, float] = (0.2, -0.05),
                   rolling_m: float = CARPET_ROLLING_M) -> str:
    ball = _BALL.format(x=ball_xy[0], y=ball_xy[1], z=BALL_RADIUS_M + 1e-4, r=BALL_RADIUS_M,
                        m=BALL_MASS_KG, roll=rolling_m)
    return scene_xml(bodies=ball, sensors=SOLE_SENSORS)


@lru_cache(maxsize=4)
def load_scene(rolling_m: float = CARPET_ROLLING_M) -> mujoco.MjModel:
    """The kick scene with **elliptic** friction cones: MuJoCo's default pyramidal cones align
    their edges with each contact's frame (the floor's x/y axes), so friction, and with it the
    direction a ball is kicked, depended on the robot's heading in the world (a 0 deg kick went
    +13.7 deg with the robot turned 21 deg); elliptic cones are rotation invariant."""
    model = mujoco.MjModel.from_xml_string(kick_scene_xml(rolling_m=rolling_m))
    model.opt.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    return model


def ball_qpos_index(model: mujoco.MjModel) -> int:
    return nao.qpos_address(model, BALL_JOINT)


def ball_qvel_index(model: mujoco.MjModel) -> int:
    return nao.qvel_address(model, BALL_JOINT)


def initial_scene_state(model: mujoco.MjModel, ball_xy: np.ndarray,
                        pose: np.ndarray | None = None) -> np.ndarray:
    """Full-physics state: the NAO in ``pose`` (default the crouch) and the ball resting at
    ``ball_xy`` (world)."""
    data = nao.initial_data(model, pose)
    i = ball_qpos_index(model)
    data.qpos[i:i + 3] = [ball_xy[0], ball_xy[1], BALL_RADIUS_M + 1e-4]
    data.qpos[i + 3:i + 7] = [1, 0, 0, 0]
    mujoco.mj_forward(model, data)
    return nao.get_state(model, data)


def default_ball_xy(model: mujoco.MjModel, gap_m: float = 0.02, pose: np.ndarray | None = None,
                    foot: str = "r") -> np.ndarray:
    """Ball ``gap_m`` in front of the ``foot`` ("l"/"r") sole's toe, centred on the sole."""
    data = nao.initial_data(model, pose)
    sole = data.site(f"{foot}_sole_site").xpos
    return np.array([sole[0] + SOLE_HALF_M[0] + BALL_RADIUS_M + gap_m, sole[1]])


def studio_state(model: mujoco.MjModel, pose: np.ndarray) -> np.ndarray:
    """The studio's kick scene: the NAO at rest in ``pose``, the ball in front of its right
    foot (:func:`default_ball_xy`)."""
    return initial_scene_state(model, default_ball_xy(model, pose=pose), pose)


def rolling_deceleration(rolling_m: float, g: float = 9.81) -> float:
    """Deceleration (m/s^2) of a solid ball rolling without slipping under rolling friction."""
    return rolling_m * g / (1.4 * BALL_RADIUS_M)


@lru_cache(maxsize=4)
def measured_deceleration(rolling_m: float = CARPET_ROLLING_M, v0_m_s: float = 1.5) -> float:
    """Rolling deceleration (m/s^2) measured in the scene: the ball rolls alone (far from the
    robot) from ``v0_m_s`` for 1 s; slope of its speed (with the elliptic cones of
    :func:`load_scene` within 0.1 % of :func:`rolling_deceleration`: 0.3504 m/s^2 at
    :data:`CARPET_ROLLING_M`, 0.7003 at the old 0.005 m)."""
    model = load_scene(rolling_m)
    return rolling_slope(model, initial_scene_state(model, np.array([1.0, 0.5])), v0_m_s)


def rolling_slope(model: mujoco.MjModel, state: np.ndarray, v0_m_s: float = 1.5) -> float:
    """The ball's rolling deceleration (m/s^2) in any kick scene ``model`` from ``state`` (the
    ball far from the robot): rolled from ``v0_m_s`` along x for 1 s, slope of its speed
    after the first tenth (a line fitted by least squares)."""
    data = mujoco.MjData(model)
    mujoco.mj_setState(model, data, state, nao.STATE_SPEC)
    iv = ball_qvel_index(model)
    data.qvel[iv:iv + 6] = [v0_m_s, 0, 0, 0, v0_m_s / BALL_RADIUS_M, 0]
    n = int(round(1.0 / model.opt.timestep))
    v = np.empty(n)
    for k in range(n):
        mujoco.mj_step(model, data)
        v[k] = data.qvel[iv]
    t = model.opt.timestep * np.arange(1, n + 1)
    return float(-np.polyfit(t[n // 10:], v[n // 10:], 1)[0])


def calibrated_rolling_m(deceleration_m_s2: float = CARPET_DECELERATION_M_S2,
                         tol_m_s2: float = 1e-4) -> float:
    """The rolling friction (m) whose :func:`measured_deceleration` is ``deceleration_m_s2``:
    bisection (the deceleration grows monotonically with the friction) between 0 and
    3x the solid-ball formula's value."""
    lo, hi = 0.0, 3.0 * deceleration_m_s2 * 1.4 * BALL_RADIUS_M / 9.81
    mid = hi / 2
    for _ in range(40):
        mid = 0.5 * (lo + hi)
        a = measured_deceleration.__wrapped__(mid)
        if abs(a - deceleration_m_s2) <= tol_m_s2:
            break
        lo, hi = (mid, hi) if a < deceleration_m_s2 else (lo, mid)
    return mid
