"""The kick scene of any biped of :mod:`evomotion.sim.robots`: its model plus the SPL ball.

The NAO's scene (:mod:`.scene`) inserts MJCF text into the NAO's own file; another robot's
scene is built with :class:`mujoco.MjSpec` from the robot's edited model (``Robot.xml``, the
position servos and sole sites of :mod:`evomotion.sim.robots.build`), with what
:mod:`.scene` adds to the NAO:

- the ball of :mod:`.scene` (100 mm, 45 g, ``condim = 6``, rolling friction ``rolling_m``),
  colliding with the floor and with the robot's geoms (its ``contype``/``conaffinity`` bits are
  read from the floor and the feet, so it meets them whatever bits the MJCF uses);
- per foot the sensors the ZMP constraint reads (:func:`.problem.support_analysis`), named as
  the NAO's: ``l_contact``/``r_contact`` (``contact`` of the foot body with the floor, data
  ``found force pos``, reduced to the net force; MuJoCo XML reference, ``sensor/contact``),
  ``l_sole``/``r_sole`` (``framepos`` of the sole site) and ``l_xaxis``/``r_xaxis``
  (``framexaxis`` of the sole site);
- elliptic friction cones, as in the NAO's kick scene (:func:`.scene.load_scene` says why).

The support polygon's sole rectangle is read from the model: the half extents of the foot
body's collision geoms around the sole site (:func:`sole_half`).
"""

from __future__ import annotations

import mujoco
import numpy as np

from evomotion.sim.state import QPOS_OFFSET, get_state, qpos_address
from evomotion.studies.biped_kick.scene import BALL_JOINT, BALL_MASS_KG, BALL_RADIUS_M

#: the NAO scene's sensor prefix of each foot of a robot spec
PREFIX = {"left": "l", "right": "r"}
#: contact sensor data ``found force pos`` (bits of mjtConDataField) and ``netforce`` reduction
CONTACT_DATA, CONTACT_NETFORCE = 1 | 2 | 16, 3


def _collision_geoms(model: mujoco.MjModel, body: int) -> list[int]:
    return [g for g in range(model.ngeom) if model.geom_bodyid[g] == body
            and (model.geom_contype[g] or model.geom_conaffinity[g])]


def _ball_bits(robot) -> tuple[int, int]:
    """(contype, conaffinity) for a ball that touches the floor and the robot's feet."""
    m = robot.model
    floor = m.geom(robot.spec.floor).id
    feet = [g for b in robot.spec.feet.values() for g in _collision_geoms(m, m.body(b).id)]
    contype = int(m.geom_conaffinity[floor]) | int(np.bitwise_or.reduce(m.geom_conaffinity[feet]))
    affinity = int(m.geom_contype[floor]) | int(np.bitwise_or.reduce(m.geom_contype[feet]))
    return contype, affinity


def scene_spec(robot, rolling_m: float) -> mujoco.MjSpec:
    """The robot's model with the ball and the sole sensors (see the module doc)."""
    spec = mujoco.MjSpec.from_string(robot.xml, assets=robot.assets)
    contype, affinity = _ball_bits(robot)
    ball = spec.worldbody.add_body(name=BALL_JOINT, pos=[0.2, -0.05, BALL_RADIUS_M + 1e-4])
    ball.add_freejoint(name=BALL_JOINT)
    # a solid sphere's inertia, set on the body: a model may not infer inertia from geoms
    ball.explicitinertial = True
    ball.mass = BALL_MASS_KG
    ball.inertia = [0.4 * BALL_MASS_KG * BALL_RADIUS_M**2] * 3
    ball.ipos, ball.iquat = [0, 0, 0], [1, 0, 0, 0]  # without them to_xml drops the inertial
    ball.add_geom(name=BALL_JOINT, type=mujoco.mjtGeom.mjGEOM_SPHERE,
                  size=[BALL_RADIUS_M, 0, 0], mass=BALL_MASS_KG, condim=6, contype=contype,
                  conaffinity=affinity, friction=[0.7, 0.005, rolling_m],
                  rgba=[0.95, 0.95, 0.95, 1])
    for foot, body in robot.spec.feet.items():
        p, site = PREFIX[foot], robot.sole_site(foot)
        spec.add_sensor(name=f"{p}_contact", type=mujoco.mjtSensor.mjSENS_CONTACT,
                        objtype=mujoco.mjtObj.mjOBJ_BODY, objname=body,
                        reftype=mujoco.mjtObj.mjOBJ_GEOM, refname=robot.spec.floor,
                        intprm=[CONTACT_DATA, CONTACT_NETFORCE, 1])
        spec.add_sensor(name=f"{p}_sole", type=mujoco.mjtSensor.mjSENS_FRAMEPOS,
                        objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site)
        spec.add_sensor(name=f"{p}_xaxis", type=mujoco.mjtSensor.mjSENS_FRAMEXAXIS,
                        objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site)
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    return spec


def sole_half(robot, foot: str = "right") -> tuple[float, float]:
    """Half length and half width (m) of the foot's sole rectangle: the largest extent of the
    foot body's collision geoms (their bounding boxes, ``geom_aabb``) from the sole site in
    the foot's x and y."""
    m = robot.model
    body = m.body(robot.spec.feet[foot]).id
    site = m.site(robot.sole_site(foot)).id
    centre = m.site_pos[site]
    hx = hy = 0.0
    for g in _collision_geoms(m, body):
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, m.geom_quat[g])
        c, h = m.geom_aabb[g, :3], m.geom_aabb[g, 3:]
        corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1) for sz in (-1, 1)])
        pts = m.geom_pos[g] + (c + corners * h) @ rot.reshape(3, 3).T
        hx = max(hx, float(np.abs(pts[:, 0] - centre[0]).max()))
        hy = max(hy, float(np.abs(pts[:, 1] - centre[1]).max()))
    return hx, hy


def initial_state(model: mujoco.MjModel, robot, ball_xy: np.ndarray) -> np.ndarray:
    """Full-physics state of the scene: the robot as in its own initial state
    (``Robot.state0``: its pose, the soles just above the floor) and the ball at rest at
    ``ball_xy`` (world)."""
    data = mujoco.MjData(model)
    nq = robot.model.nq  # the robot's joints come first; the ball's free joint after them
    data.qpos[:nq] = robot.state0[QPOS_OFFSET:QPOS_OFFSET + nq]
    data.ctrl[:] = robot.pose
    i = qpos_address(model, BALL_JOINT)
    data.qpos[i:i + 3] = [ball_xy[0], ball_xy[1], BALL_RADIUS_M + 1e-4]
    data.qpos[i + 3:i + 7] = [1, 0, 0, 0]
    mujoco.mj_forward(model, data)
    return get_state(model, data)
