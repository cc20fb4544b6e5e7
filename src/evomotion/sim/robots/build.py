"""Build a simulated robot from its :class:`~.spec.RobotSpec` with :class:`mujoco.MjSpec`.

The MJCF and every file it names are read by :mod:`.mjcf` (bounded, inside the spec's
folder, includes expanded there) and compiled from memory; every compiled model is checked by
:func:`~.limits.check_model` (sizes, finite values, physical ranges) before an ``MjData`` is
made. Then, with ``MjSpec`` (never by editing text):

- with ``[servo]``, the integrator becomes ``implicitfast`` when the MJCF used Euler (stiff
  servos on light links need implicit damping), and every motor (``gaintype`` fixed, no
  bias) becomes a position servo on its joint: ``kp``/``kv`` of the spec, control range = the
  joint's range, torque limited to the motor's ``gear x ctrlrange`` (``force = "gear"``)
  or to ``force``;
- per foot a site at the centre of the foot body's collision geoms, a ``framepos`` sensor of it
  (``<foot>_pos``) and a ``contact`` sensor between the foot body and the floor (``<foot>_floor``,
  1 while it touches).

Then the checks against the model (each a ``FILE:LINE`` :class:`InputError`): the torso has
the free joint, every foot body exists and has collision geoms (the soles), every ``[pose]``
and ``[evolve]`` joint exists, is driven by an actuator and lies within the joint's limits,
and no motor is left without a ``[servo]``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass, field
from pathlib import Path

import mujoco
import numpy as np

from evomotion.errors import InputError
from evomotion.sim.robots.limits import check_model
from evomotion.sim.robots.mjcf import MjcfBundle, confined, read_mjcf, remember_assets
from evomotion.sim.robots.spec import RobotSpec
from evomotion.sim.state import STATE_SPEC


@dataclass(frozen=True)
class Robot:
    """A robot ready to simulate: ``model``; ``joints`` driven by the actuators (actuator
    order); the ``evolved`` joints, their actuator ``columns`` and ranges ``lower``/``upper``;
    the initial targets ``pose[nu]`` and state ``state0``; the ``feet`` and fall thresholds."""

    spec: RobotSpec
    model: mujoco.MjModel
    joints: tuple[str, ...]
    evolved: tuple[str, ...]
    columns: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    pose: np.ndarray
    state0: np.ndarray
    feet: tuple[str, ...]
    xml: str = ""  # the edited model as MJCF text (for videos)
    #: the walk study's gait roles: role -> ((actuator column, sign) per leg)
    gait: dict[str, tuple[tuple[int, float], ...]] = field(default_factory=dict)
    #: the files the MJCF names (meshes, textures), by their names in ``xml``
    assets: dict[str, bytes] = field(default_factory=dict, repr=False, compare=False)
    mjcf_sha256: str = ""  # of the MJCF file as read
    #: capability -> module providing it (a bundled robot's own code; see :meth:`capability`)
    capabilities: dict[str, str] = field(default_factory=dict, compare=False)

    @property
    def mass_kg(self) -> float:
        """The robot's total mass (kg): the spec's published ``mass_kg``, else the model's."""
        m = self.spec.mass_kg
        return float(self.model.body_mass.sum()) if m is None else m

    def has(self, capability: str) -> bool:
        """Does this robot have ``capability`` (:data:`~.spec.CAPABILITIES`)?"""
        return capability in self.capabilities

    def capability(self, capability: str, needed_by: str):
        """The module providing ``capability``; one :class:`InputError` line naming
        ``needed_by`` when this robot lacks it."""
        import importlib

        from evomotion.sim.robots.spec import CAPABILITIES

        if capability not in self.capabilities:
            raise InputError(f"{needed_by} needs {CAPABILITIES.get(capability, capability)} "
                             f"(capability {capability!r}), which robot {self.name!r} "
                             f"({self.spec.path}) does not have")
        return importlib.import_module(self.capabilities[capability])

    @property
    def gait_kind(self) -> str | None:
        return self.spec.gait_kind

    @property
    def name(self) -> str:
        return self.spec.name

    @property
    def fall_height_m(self) -> float:
        return self.spec.fall_height_m

    @property
    def fall_tilt_rad(self) -> float:
        return self.spec.fall_tilt_rad

    def fall_thresholds(self, height_m: float, tilt_rad: float) -> tuple[float, float]:
        """(height m, tilt rad) a study uses: its configured values, where they are set to
        something other than the NAO's defaults, else this robot's ``[fall]`` ones."""
        from evomotion.sim.robots.nao.constants import FALL_HEIGHT_M, FALL_TILT_RAD

        return (self.fall_height_m if height_m == FALL_HEIGHT_M else height_m,
                self.fall_tilt_rad if tilt_rad == FALL_TILT_RAD else tilt_rad)

    def sole_site(self, foot: str) -> str:
        """The site whose position is the foot's sole (``[soles]``, else the one added)."""
        return self.spec.soles.get(foot, f"{foot}_sole")

    def state_at(self, pose: np.ndarray) -> np.ndarray:
        """The initial state (``mjSTATE_FULLPHYSICS``) with the actuators' targets and the
        joints at ``pose[nu]`` instead of the spec's pose (:func:`initial_state`)."""
        return initial_state(self.spec, self.model, self.joints, np.asarray(pose, float))

    def sensor(self, name: str) -> slice:
        """Slice of ``sensordata`` of the sensor ``name`` (``<foot>_pos``, ``<foot>_floor``)."""
        i = self.model.sensor(name).id
        adr, dim = int(self.model.sensor_adr[i]), int(self.model.sensor_dim[i])
        return slice(adr, adr + dim)


def mjcf_root(spec: RobotSpec) -> tuple[Path, Path]:
    """(the real path of the MJCF a spec names, the folder every file it names must lie in):
    relative to the spec (inside the spec's folder), ``evomotion:`` (in this package) or
    ``dm_control:`` (in the installed dm_control, found without importing it)."""
    ref = spec.mjcf
    if ref.startswith("evomotion:"):
        root, ref = Path(__file__).resolve().parents[2], ref.split(":", 1)[1]
    elif ref.startswith("dm_control:"):
        import importlib.util

        found = importlib.util.find_spec("dm_control")
        if found is None or not found.submodule_search_locations:
            raise spec.error("robot", "mjcf", f"{ref!r} needs dm_control: pip install "
                             "'evomotion[robots]'")
        root, ref = Path(list(found.submodule_search_locations)[0]), ref.split(":", 1)[1]
    else:
        root = spec.path.parent
    root = Path(os.path.realpath(root))
    try:
        path = confined(ref, root, root)
    except ValueError as e:
        raise spec.error("robot", "mjcf", f"{ref[:80]!r}: {e}") from None
    if not path.exists():
        raise spec.error("robot", "mjcf", f"no such MJCF file {path}")
    return path, root


def resolve_mjcf(spec: RobotSpec) -> Path:
    """The real path of the MJCF file a spec names (:func:`mjcf_root`)."""
    return mjcf_root(spec)[0]


def read_model(spec: RobotSpec) -> MjcfBundle:
    """The spec's MJCF and every file it names, read with bounds (:mod:`.mjcf`); one line
    naming the spec (and the MJCF file and line) for anything refused."""
    path, root = mjcf_root(spec)
    try:
        return read_mjcf(path, root)
    except InputError as e:
        raise spec.error("robot", "mjcf", _one_line(e)) from None


def _compile(spec: RobotSpec, mj: mujoco.MjSpec, bundle: MjcfBundle, key: str,
             what: str) -> mujoco.MjModel:
    """``mj`` compiled and checked (:func:`~.limits.check_model`), or one line."""
    try:
        model = mj.compile()
    except (ValueError, RuntimeError, TypeError) as e:
        raise spec.error("robot", key, f"{what}: {bundle.locate(_one_line(e))}") from None
    check_model(model, lambda m: spec.error("robot", "mjcf", f"{bundle.path}: {m}"))
    return model


def _servos(spec: RobotSpec, mj: mujoco.MjSpec, model: mujoco.MjModel) -> None:
    motors = [a for a in mj.actuators
              if a.gaintype == mujoco.mjtGain.mjGAIN_FIXED
              and a.biastype == mujoco.mjtBias.mjBIAS_NONE]
    if motors and spec.servo is None:
        raise spec.error("robot", "mjcf", f"the MJCF drives {len(motors)} joints with motors "
                         f"(e.g. {motors[0].target!r}); add a [servo] section (kp, kv, force) "
                         "to make them position servos")
    if spec.servo is None:
        return
    kp, kv, force = spec.servo["kp"], spec.servo["kv"], spec.servo["force"]
    if mj.option.integrator == mujoco.mjtIntegrator.mjINT_EULER:
        # stiff servos on light links are unstable with explicit Euler damping
        mj.option.integrator = mujoco.mjtIntegrator.mjINT_IMPLICITFAST
    for a in motors:
        if a.trntype != mujoco.mjtTrn.mjTRN_JOINT:
            raise spec.error("servo", None, f"actuator {a.name!r} does not drive a joint")
        jid = model.joint(a.target).id
        lo, hi = model.jnt_range[jid] if model.jnt_limited[jid] else (-np.pi, np.pi)
        ranged = a.ctrlrange[1] > a.ctrlrange[0]  # a motor without a range: |ctrl| <= 1
        peak = max(abs(a.ctrlrange[0]), abs(a.ctrlrange[1])) if ranged else 1.0
        limit = abs(float(a.gear[0])) * float(peak) if force == "gear" else float(force)
        a.set_to_position(kp=kp, kv=kv)
        a.gear = [1, 0, 0, 0, 0, 0]
        a.ctrlrange = [float(lo), float(hi)]
        a.ctrllimited = True
        a.forcerange = [-limit, limit]
        a.forcelimited = True


def _feet(spec: RobotSpec, mj: mujoco.MjSpec, model: mujoco.MjModel) -> None:
    for foot, body_name in spec.feet.items():
        try:
            bid = model.body(body_name).id
        except KeyError:
            raise spec.error("feet", foot, f"no body {body_name!r} in the MJCF") from None
        geoms = [g for g in range(model.ngeom) if model.geom_bodyid[g] == bid
                 and (model.geom_contype[g] or model.geom_conaffinity[g])]
        if not geoms:
            raise spec.error("feet", foot, f"body {body_name!r} has no collision geoms (no "
                             "sole geoms)")
        site = spec.soles.get(foot)
        if site is None:
            site = f"{foot}_sole"
            centre = model.geom_pos[geoms].mean(axis=0)
            mj.body(body_name).add_site(name=site, pos=centre, size=[0.005, 0, 0])
        else:
            try:
                sid = model.site(site).id
            except KeyError:
                raise spec.error("soles", foot, f"no site {site!r} in the MJCF") from None
            if model.site_bodyid[sid] != bid:
                raise spec.error("soles", foot, f"site {site!r} is not on the foot body "
                                 f"{body_name!r}")
        mj.add_sensor(name=f"{foot}_pos", type=mujoco.mjtSensor.mjSENS_FRAMEPOS,
                      objtype=mujoco.mjtObj.mjOBJ_SITE, objname=site)
        mj.add_sensor(name=f"{foot}_floor", type=mujoco.mjtSensor.mjSENS_CONTACT,
                      objtype=mujoco.mjtObj.mjOBJ_BODY, objname=body_name,
                      reftype=mujoco.mjtObj.mjOBJ_GEOM, refname=spec.floor,
                      intprm=[1, 0, 1])  # data "found", no reduction, 1 match


def build_robot(spec: RobotSpec) -> Robot:
    """Load, edit, compile and check the robot of ``spec`` (see the module doc)."""
    bundle = read_model(spec)
    try:
        mj = mujoco.MjSpec.from_string(bundle.xml, assets=bundle.assets)
    except (ValueError, RuntimeError, TypeError) as e:
        raise spec.error("robot", "mjcf", f"{bundle.path} does not load: "
                         f"{bundle.locate(_one_line(e))}") from None
    base = _compile(spec, mj, bundle, "mjcf", f"{bundle.path} does not compile")
    if spec.remove:
        for body in spec.remove:
            try:
                mj.delete(mj.body(body))
            except (TypeError, ValueError, KeyError):
                raise spec.error("robot", "remove", f"no body {body!r} to remove") from None
        base = _compile(spec, mj, bundle, "remove", "the model does not compile without "
                        f"{', '.join(spec.remove)}")
    try:
        base.geom(spec.floor)
    except KeyError:
        raise spec.error("robot", "floor", f"no geom {spec.floor!r} in the MJCF") from None
    try:
        torso = base.body(spec.torso).id
    except KeyError:
        raise spec.error("robot", "torso", f"no body {spec.torso!r} in the MJCF") from None
    free = [j for j in range(base.njnt) if base.jnt_bodyid[j] == torso
            and base.jnt_type[j] == mujoco.mjtJoint.mjJNT_FREE]
    if not free or base.jnt_qposadr[free[0]] != 0:
        raise spec.error("robot", "torso", f"body {spec.torso!r} must carry the model's first "
                         "joint, a free joint")
    if spec.keyframe is not None:
        key = next((k for k in mj.keys if k.name == spec.keyframe), None)
        if key is not None and len(key.qpos) not in (0, base.nq):
            raise spec.error("robot", "keyframe", f"keyframe {spec.keyframe!r} has "
                             f"{len(key.qpos)} qpos values, the model {base.nq}")
    _servos(spec, mj, base)
    _feet(spec, mj, base)
    model = _compile(spec, mj, bundle, "mjcf", "the edited model does not compile")
    joints = channels(model)
    for section, values in (("pose", spec.pose), ("evolve", spec.evolve)):
        for name, value in values.items():
            _check_joint(spec, model, joints, section, name, value)
    gait = {role: tuple(_gait_channel(spec, joints, role, c) for c in chans)
            for role, chans in spec.gait.items()}
    pose = _initial_targets(spec, model, joints)
    evolved = tuple(spec.evolve)
    columns = np.array([joints.index(j) for j in evolved], dtype=np.int64)
    lower = np.array([spec.evolve[j][0] for j in evolved])
    upper = np.array([spec.evolve[j][1] for j in evolved])
    state0 = initial_state(spec, model, joints, pose)
    if state0[3] <= spec.fall_height_m:  # time, then the free joint's x, y, z
        raise spec.error("fall", "height_m", f"{spec.fall_height_m} m: the torso starts at "
                         f"{state0[3]:.3f} m, so every rollout would start fallen")
    try:
        xml = mj.to_xml()
    except (ValueError, RuntimeError):  # e.g. meshes that cannot be written back
        xml = ""
    if xml:
        remember_assets(xml, bundle.assets)
    return Robot(spec, model, joints, evolved, columns, lower, upper, pose, state0,
                 tuple(spec.feet), xml, gait, bundle.assets, bundle.sha256)


def channels(model: mujoco.MjModel) -> tuple[str, ...]:
    """One name per actuator: its joint's name, or the actuator's own for other transmissions
    (tendons)."""
    out = []
    for a in range(model.nu):
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT:
            out.append(model.joint(int(model.actuator_trnid[a, 0])).name)
        else:
            out.append(model.actuator(a).name)
    return tuple(out)


def _gait_channel(spec: RobotSpec, joints, role: str, channel: str) -> tuple[int, float]:
    name, sign = channel.lstrip("-"), -1.0 if channel.startswith("-") else 1.0
    if name not in joints:
        raise spec.error("gait", role, f"unknown channel {name!r}; actuated: "
                         f"{', '.join(joints)}")
    return joints.index(name), sign


def _check_joint(spec: RobotSpec, model, joints, section: str, name: str, value) -> None:
    try:
        jid = model.joint(name).id
    except KeyError:
        jid = None
        if name not in joints:
            raise spec.error(section, name, f"unknown joint {name!r}; actuated joints: "
                             f"{', '.join(joints)}") from None
    if name not in joints:
        raise spec.error(section, name, f"joint {name!r} has no actuator")
    a = joints.index(name)
    limited = model.jnt_limited[jid] if jid is not None else model.actuator_ctrllimited[a]
    if limited:
        lo, hi = (float(v) for v in (model.jnt_range[jid] if jid is not None
                                      else model.actuator_ctrlrange[a]))
        vals = value if isinstance(value, tuple) else (value,)
        if min(vals) < lo - 1e-9 or max(vals) > hi + 1e-9:
            shown = f"[{vals[0]:.6g}, {vals[1]:.6g}]" if len(vals) == 2 else f"{vals[0]:.6g}"
            raise spec.error(section, name, f"{shown} is outside the model's joint range "
                             f"[{lo:.4g}, {hi:.4g}] rad")


def _initial_targets(spec: RobotSpec, model, joints) -> np.ndarray:
    qpos = _keyframe_qpos(spec, model)
    pose = np.array([qpos[model.jnt_qposadr[model.joint(j).id]]
                     if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT else 0.0
                     for a, j in enumerate(joints)])
    for j, v in spec.pose.items():
        pose[joints.index(j)] = v
    return pose


def _keyframe_qpos(spec: RobotSpec, model) -> np.ndarray:
    if spec.keyframe is None:
        return model.qpos0.copy()
    try:
        return model.key(spec.keyframe).qpos.copy()
    except KeyError:
        raise spec.error("robot", "keyframe", f"no keyframe {spec.keyframe!r}") from None


def initial_state(spec: RobotSpec, model, joints, pose: np.ndarray) -> np.ndarray:
    """The robot at rest in ``pose``, upright facing +x, the lowest foot geom
    ``clearance_m`` above the floor (``mjSTATE_FULLPHYSICS``); with ``[soles]``, the lowest
    sole site ``clearance_m`` above it (the torso raised from the MJCF's own height by the
    difference: :func:`evomotion.sim.robots.nao.initial_data`'s rule, bit for bit)."""
    data = mujoco.MjData(model)
    data.qpos[:] = _keyframe_qpos(spec, model)
    data.qpos[3:7] = (1.0, 0.0, 0.0, 0.0)
    for a, (j, v) in enumerate(zip(joints, pose, strict=True)):
        if model.actuator_trntype[a] == mujoco.mjtTrn.mjTRN_JOINT:
            data.qpos[model.jnt_qposadr[model.joint(j).id]] = v
    data.ctrl[:] = pose
    if spec.soles:
        mujoco.mj_kinematics(model, data)
        low = min(float(data.site(s).xpos[2]) for s in spec.soles.values())
        data.qpos[2] += spec.clearance_m - low
        mujoco.mj_forward(model, data)
        return _state(model, data)
    data.qpos[2] = 0.0
    mujoco.mj_kinematics(model, data)
    feet = {model.body(b).id for b in spec.feet.values()}
    low = min(_lowest_z(model, data, g) for g in range(model.ngeom)
              if model.geom_bodyid[g] in feet)
    data.qpos[2] = spec.clearance_m - low
    mujoco.mj_forward(model, data)
    return _state(model, data)


def _state(model, data) -> np.ndarray:
    state = np.empty(mujoco.mj_stateSize(model, STATE_SPEC))
    mujoco.mj_getState(model, data, state, STATE_SPEC)
    return state


def _lowest_z(model, data, g: int) -> float:
    """Lowest world z of geom ``g``'s bounding box (its 8 corners, rotated)."""
    centre, half = model.geom_aabb[g, :3], model.geom_aabb[g, 3:]
    corners = centre + half * np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                                        for sz in (-1, 1)])
    world = data.geom_xpos[g] + corners @ data.geom_xmat[g].reshape(3, 3).T
    return float(world[:, 2].min())


def _one_line(e: Exception) -> str:
    return " ".join(str(e).split())
