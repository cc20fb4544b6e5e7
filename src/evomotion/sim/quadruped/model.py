"""The MuJoCo quadruped for paper-003 walking plans (Ondroušek & Březina), built with MjSpec.

Planning model (paper 003, section 3.1, Tab. 1), in paper units: a rectangular body ``a x b``
(``a`` along body X, ``b`` along body Y, the walking axis), hips at the corners (leg 0
front-left (-a/2, +b/2), 1 rear-left (-a/2, -b/2), 2 rear-right (+a/2, -b/2), 3 front-right
(+a/2, +b/2)); each foot within an annular sector about its hip (distance in
[l_min, l_max], angle within ``sector_half_width`` of pi for legs 0, 1 and of 0 for legs 2, 3).
One paper unit is ``unit_m`` metres in the simulation; everything else here is SI (m, kg, s,
rad, N m).

Each leg: hip yaw (about the body's vertical), hip pitch, knee pitch (both about the leg's
horizontal normal), a thigh and a shank capsule and a sphere foot. Yaw 0 points the leg along
its sector's nominal direction; positive pitch turns the link downwards. The knee bends
upwards (insect-like), see :mod:`.ik`. Legs collide with the floor only (never with the
torso or each other); the torso box collides with the floor, and a contact sensor reports it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, fields

import mujoco
import numpy as np

from evomotion.sim.quadruped.geometry import (
    BODY_A,
    BODY_B,
    L_MAX,
    L_MIN,
    NOMINAL_ANGLES,
    SECTOR_HALF_WIDTH,
    hip_positions,
)

TORSO = "torso"
FLOOR = "floor"
LEG_NAMES = ("front_left", "rear_left", "rear_right", "front_right")
JOINT_KINDS = ("yaw", "pitch", "knee")
FOOT_SENSOR_DIM = 7  # contact sensor: found, force[3] (floor on foot, world), pos[3]
REACH_SLACK = 0.1  # keep the hip-foot distance within 10 % of the links' reach limits
YAW_LIMIT_SLACK = 0.35  # [rad] hip yaw range beyond the sector's half width
MAX_BODY_M = 5.0  # [m] the longest torso side (the legs reach 0.3 m)


@dataclass(frozen=True)
class QuadrupedSpec:
    """Geometry (paper units for the planning model, SI for the rest) and actuation.

    The torso (2 kg) outweighs the four legs together (0.2 kg) 10 to 1, and most of a leg's
    mass sits in its hip housing (fixed to the torso), so a swinging leg (0.02 kg moving)
    barely shifts the centre of mass. ``body_height_m`` is the height of the torso centre
    and of the hip joints above the floor. ``kp`` [N m/rad] / ``kv`` [N m s/rad]: position
    servo gains; ``armature`` [kg m^2]: reflected rotor inertia of each joint.
    ``max_lift_m``: the highest swing lift checked for reach in :meth:`check`.
    """

    a: float = BODY_A
    b: float = BODY_B
    l_min: float = L_MIN
    l_max: float = L_MAX
    sector_half_width: float = SECTOR_HALF_WIDTH
    unit_m: float = 0.1
    body_height_m: float = 0.14
    torso_thickness_m: float = 0.04
    torso_mass_kg: float = 2.0
    thigh_m: float = 0.15
    shank_m: float = 0.15
    link_radius_m: float = 0.007
    foot_radius_m: float = 0.012
    hip_mass_kg: float = 0.03
    thigh_mass_kg: float = 0.01
    shank_mass_kg: float = 0.006
    foot_mass_kg: float = 0.004
    kp: float = 800.0
    kv: float = 6.0
    armature: float = 0.01
    friction: float = 1.0
    timestep: float = 0.002
    max_lift_m: float = 0.04

    def __post_init__(self) -> None:
        self.check()

    def hips_m(self) -> np.ndarray:
        """Hip joint positions in the torso frame, ``[4, 3]`` metres (z = 0)."""
        u = self.unit_m  # (a / 2) * u: the same floats as 0.5 * a * u
        return np.array([[x * u, y * u, 0.0] for x, y in hip_positions(self.a, self.b)])

    @property
    def foot_drop_m(self) -> float:
        """Height of the hips above a standing foot's centre [m]."""
        return self.body_height_m - self.foot_radius_m

    @property
    def leg_mass_kg(self) -> float:
        return self.hip_mass_kg + self.thigh_mass_kg + self.shank_mass_kg + self.foot_mass_kg

    @property
    def total_mass_kg(self) -> float:
        return self.torso_mass_kg + 4 * self.leg_mass_kg

    def reach_limits_m(self) -> tuple[float, float]:
        """The hip-foot distances the legs may use, with ``REACH_SLACK`` of margin [m]."""
        span = self.thigh_m + self.shank_m
        return abs(self.thigh_m - self.shank_m) + REACH_SLACK * span, (1 - REACH_SLACK) * span

    def check(self) -> None:
        """ValueError unless every field is a finite number, the torso's sides are at most
        ``MAX_BODY_M``, every sector position is reachable for feet between the floor and
        ``max_lift_m`` above it, and the body clears the floor."""
        bad = [f.name for f in fields(self) if isinstance(getattr(self, f.name), bool) or
               not isinstance(getattr(self, f.name), int | float) or
               not math.isfinite(getattr(self, f.name))]
        if bad:
            raise ValueError(f"{bad[0]}: expected a finite number, got {getattr(self, bad[0])!r}")
        if max(self.a, self.b) * self.unit_m > MAX_BODY_M:
            raise ValueError(f"the torso ({self.a:.6g} x {self.b:.6g} units of {self.unit_m:g} "
                             f"m) is larger than {MAX_BODY_M:g} m a side")
        if not (0 < self.l_min < self.l_max and 0 < self.sector_half_width < math.pi / 2):
            raise ValueError("need 0 < l_min < l_max and 0 < sector_half_width < pi/2")
        if min(self.a, self.b, self.unit_m, self.timestep, self.torso_mass_kg) <= 0:
            raise ValueError("a, b, unit_m, timestep and torso_mass_kg must be positive")
        lo, hi = self.reach_limits_m()
        drop = self.foot_drop_m
        near = math.hypot(self.l_min * self.unit_m, drop - self.max_lift_m)
        far = math.hypot(self.l_max * self.unit_m, drop)
        if drop - self.max_lift_m <= 0 or near < lo or far > hi:
            raise ValueError(f"legs cannot reach the sector: hip-foot distance in "
                             f"[{near:.4f}, {far:.4f}] m, links allow [{lo:.4f}, {hi:.4f}] m")
        if self.body_height_m - 0.5 * self.torso_thickness_m <= 0:
            raise ValueError("the torso would start below the floor")


def _material(spec: mujoco.MjSpec) -> None:
    tex = spec.add_texture(name="grid", type=mujoco.mjtTexture.mjTEXTURE_2D,
                           builtin=mujoco.mjtBuiltin.mjBUILTIN_CHECKER, width=256, height=256,
                           rgb1=[0.82, 0.84, 0.86], rgb2=[0.7, 0.72, 0.75])
    mat = spec.add_material(name="grid", texrepeat=[10, 10], reflectance=0.0)
    mat.textures[mujoco.mjtTextureRole.mjTEXROLE_RGB] = tex.name


def _add_leg(spec: mujoco.MjSpec, torso: mujoco.MjsBody, s: QuadrupedSpec, i: int) -> None:
    name, hip = LEG_NAMES[i], s.hips_m()[i]
    nominal = NOMINAL_ANGLES[i]
    legs = dict(contype=2, conaffinity=0, friction=[s.friction, 0.005, 0.0001])
    yaw_lim = s.sector_half_width + YAW_LIMIT_SLACK
    hipb = torso.add_body(name=f"{name}_hip", pos=hip.tolist(),
                          quat=[math.cos(nominal / 2), 0.0, 0.0, math.sin(nominal / 2)])
    hipb.add_geom(type=mujoco.mjtGeom.mjGEOM_SPHERE, size=[0.016, 0, 0], mass=s.hip_mass_kg,
                  rgba=[0.25, 0.25, 0.28, 1], contype=0, conaffinity=0)
    hipb.add_joint(name=f"{name}_yaw", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 0, 1],
                   range=[-yaw_lim, yaw_lim], armature=s.armature)
    thigh = hipb.add_body(name=f"{name}_thigh")
    thigh.add_joint(name=f"{name}_pitch", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0],
                    range=[-1.6, 1.2], armature=s.armature)
    thigh.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[s.link_radius_m, 0, 0],
                   fromto=[0, 0, 0, s.thigh_m, 0, 0], mass=s.thigh_mass_kg,
                   rgba=[0.85, 0.5, 0.15, 1], **legs)
    shank = thigh.add_body(name=f"{name}_shank", pos=[s.thigh_m, 0, 0])
    shank.add_joint(name=f"{name}_knee", type=mujoco.mjtJoint.mjJNT_HINGE, axis=[0, 1, 0],
                    range=[0.05, 3.0], armature=s.armature)
    shank.add_geom(type=mujoco.mjtGeom.mjGEOM_CAPSULE, size=[0.8 * s.link_radius_m, 0, 0],
                   fromto=[0, 0, 0, s.shank_m, 0, 0], mass=s.shank_mass_kg,
                   rgba=[0.3, 0.3, 0.32, 1], **legs)
    shank.add_geom(name=f"{name}_foot", type=mujoco.mjtGeom.mjGEOM_SPHERE,
                   size=[s.foot_radius_m, 0, 0], pos=[s.shank_m, 0, 0], mass=s.foot_mass_kg,
                   rgba=[0.1, 0.1, 0.1, 1], **legs)
    shank.add_site(name=f"{name}_foot", pos=[s.shank_m, 0, 0], size=[0.005, 0, 0])
    for kind in JOINT_KINDS:
        act = spec.add_actuator(name=f"{name}_{kind}", target=f"{name}_{kind}",
                                trntype=mujoco.mjtTrn.mjTRN_JOINT)
        act.set_to_position(kp=s.kp, kv=s.kv)
    spec.add_sensor(name=f"{name}_contact", type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=mujoco.mjtObj.mjOBJ_GEOM, objname=FLOOR,
                    reftype=mujoco.mjtObj.mjOBJ_GEOM, refname=f"{name}_foot",
                    intprm=[1 | 2 | 16, 3, 1])  # data="found force pos", reduce="netforce"


def build_spec(s: QuadrupedSpec = QuadrupedSpec()) -> mujoco.MjSpec:
    """The model as an editable :class:`mujoco.MjSpec`."""
    spec = mujoco.MjSpec()
    spec.modelname = "paper003_quadruped"
    spec.compiler.degree = False
    spec.option.timestep = s.timestep
    spec.option.cone = mujoco.mjtCone.mjCONE_ELLIPTIC
    spec.option.impratio = 10.0  # elliptic cones: stiffer friction, less creep
    spec.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST  # servo damping
    spec.visual.global_.offwidth, spec.visual.global_.offheight = 1280, 960
    spec.visual.headlight.ambient = [0.35, 0.35, 0.35]
    spec.visual.headlight.diffuse = [0.5, 0.5, 0.5]
    _material(spec)
    world = spec.worldbody
    world.add_light(pos=[0, 0, 3], dir=[0, 0, -1], type=mujoco.mjtLightType.mjLIGHT_DIRECTIONAL,
                    diffuse=[0.7, 0.7, 0.7])
    world.add_geom(name=FLOOR, type=mujoco.mjtGeom.mjGEOM_PLANE, size=[0, 0, 0.05],
                   material="grid", contype=1, conaffinity=3,
                   friction=[s.friction, 0.005, 0.0001])
    torso = world.add_body(name=TORSO, pos=[0, 0, s.body_height_m])
    torso.add_freejoint(name="root")
    ax, by = 0.5 * s.a * s.unit_m, 0.5 * s.b * s.unit_m
    torso.add_geom(name=TORSO, type=mujoco.mjtGeom.mjGEOM_BOX,
                   size=[ax, by, 0.5 * s.torso_thickness_m], mass=s.torso_mass_kg,
                   rgba=[0.2, 0.45, 0.75, 1], contype=1, conaffinity=0)
    torso.add_geom(type=mujoco.mjtGeom.mjGEOM_BOX, size=[0.25 * ax, 0.02, 0.003],
                   pos=[0, by - 0.03, 0.5 * s.torso_thickness_m], rgba=[0.95, 0.95, 0.2, 1],
                   contype=0, conaffinity=0, mass=0.0, density=0.0)  # marks the front (+Y)
    for i in range(4):
        _add_leg(spec, torso, s, i)
    spec.add_sensor(name="torso_contact", type=mujoco.mjtSensor.mjSENS_CONTACT,
                    objtype=mujoco.mjtObj.mjOBJ_GEOM, objname=FLOOR,
                    reftype=mujoco.mjtObj.mjOBJ_GEOM, refname=TORSO,
                    intprm=[1 | 2, 3, 1])  # data="found force", reduce="netforce"
    return spec


def build_model(s: QuadrupedSpec = QuadrupedSpec()) -> mujoco.MjModel:
    """The compiled model: ``nq = 7 + 12``, 12 position actuators (leg-major: yaw, pitch,
    knee), sensors: per foot ``found, force[3], pos[3]`` then the torso's ``found, force``."""
    return build_spec(s).compile()


def model_xml(s: QuadrupedSpec = QuadrupedSpec()) -> str:
    """MJCF text of :func:`build_model` (for the renderer's child process)."""
    spec = build_spec(s)
    spec.compile()
    return spec.to_xml()
