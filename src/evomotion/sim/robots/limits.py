"""Bounds on a compiled robot model, checked before any ``MjData`` is made.

:func:`check_model` refuses, with one line naming the first offending field:

- a model larger than :data:`SIZE_LIMITS` (bodies, joints, geoms, ``nq``, ...) or whose
  ``MjData`` arena (``<size memory>``) exceeds :data:`MAX_ARENA_BYTES`;
- solver settings that make one step take arbitrarily long (:data:`ITERATION_LIMITS`) and
  rendering buffers larger than :data:`MAX_RENDER_PIXELS` across;
- any NaN or infinity in the model's real-valued fields;
- a physical quantity outside its range (:data:`FIELD_RANGES`: lengths in metres, masses in
  kg, inertias in kg m^2, the time step in s, joint ranges in rad or m, servo gains, ...).

These are the ranges of a legged robot (its parts, the floor it stands on); a model outside
them would run with MuJoCo's "Nan, Inf or huge value" warnings rather than simulate a robot.
"""

from __future__ import annotations

from collections.abc import Callable

import mujoco
import numpy as np

#: the most of each kind of model element
SIZE_LIMITS = {"nbody": 1000, "njnt": 1000, "ngeom": 10_000, "nsite": 10_000, "nq": 1000,
               "nv": 1000, "nu": 1000, "ntendon": 1000, "neq": 1000, "nsensor": 10_000,
               "nkey": 1000, "nmesh": 1000, "nmeshvert": 2_000_000, "nmeshface": 4_000_000,
               "ntexdata": 256 * 2**20, "nhfielddata": 16 * 2**20, "nflex": 100,
               "nflexvert": 100_000, "nskin": 100, "nuserdata": 1_000_000}
#: the largest ``MjData`` arena (bytes; ``<size memory>``), ``nconmax``, ``njmax``
MAX_ARENA_BYTES = 256 * 2**20
MAX_CONTACTS = 100_000
#: solver iterations and sampling counts of one physics step (``<option>``)
ITERATION_LIMITS = {"iterations": 1000, "ls_iterations": 1000, "noslip_iterations": 1000,
                    "ccd_iterations": 1000, "sdf_iterations": 1000, "sdf_initpoints": 1000}
MAX_RENDER_PIXELS = 8192
#: (fields, lowest, highest, unit): the physical range of each real-valued input field
FIELD_RANGES: tuple[tuple[tuple[str, ...], float, float, str], ...] = (
    (("opt.timestep",), 1e-4, 0.05, "s"),
    (("opt.gravity", "opt.wind"), -100.0, 100.0, "m/s^2 or m/s"),
    (("opt.density",), 0.0, 1e4, "kg/m^3"),
    (("opt.viscosity",), 0.0, 1e3, "Pa s"),
    (("body_mass",), 0.0, 1e4, "kg"),
    (("body_inertia",), 0.0, 1e4, "kg m^2"),
    (("body_pos", "body_ipos", "geom_pos", "geom_size", "geom_margin", "geom_gap", "site_pos",
      "site_size", "jnt_pos", "cam_pos", "light_pos", "hfield_size", "mesh_scale"),
     -1e4, 1e4, "m"),
    (("qpos0", "qpos_spring", "key_qpos", "jnt_range", "actuator_ctrlrange",
      "tendon_range"), -1e4, 1e4, "rad or m"),
    (("key_time",), 0.0, 1e6, "s"),
    (("dof_damping", "dof_armature", "dof_frictionloss", "jnt_stiffness", "jnt_margin"),
     0.0, 1e6, "SI units"),
    (("actuator_gainprm", "actuator_biasprm", "actuator_dynprm", "actuator_gear",
      "actuator_forcerange", "jnt_actfrcrange"), -1e6, 1e6, "SI units"),
    (("geom_friction",), 0.0, 100.0, "(coefficients)"),
)


def _value(model: mujoco.MjModel, name: str) -> np.ndarray | None:
    obj = model
    for part in name.split("."):
        obj = getattr(obj, part, None)
        if obj is None:
            return None
    return np.asarray(obj, dtype=float)


def check_model(model: mujoco.MjModel, error: Callable[[str], Exception]) -> None:
    """Raise ``error(message)`` for the first bound ``model`` breaks (see the module)."""
    for key, limit in SIZE_LIMITS.items():
        n = int(getattr(model, key, 0))
        if n > limit:
            raise error(f"the model is too large: {key} = {n}, expected at most {limit}")
    if model.narena > MAX_ARENA_BYTES:
        raise error(f"the model's data arena (<size memory>) is {model.narena} bytes, "
                    f"expected at most {MAX_ARENA_BYTES // 2**20} MiB")
    for key in ("nconmax", "njmax"):
        n = int(getattr(model, key, -1))
        if n > MAX_CONTACTS:
            raise error(f"<size {key}> is {n}, expected at most {MAX_CONTACTS}")
    for key, limit in ITERATION_LIMITS.items():
        n = int(getattr(model.opt, key, 0))
        if n > limit:
            raise error(f"<option {key}> is {n}, expected at most {limit}")
    quality, glob = model.vis.quality, model.vis.global_
    for name, n in (("shadowsize", quality.shadowsize), ("offwidth", glob.offwidth),
                    ("offheight", glob.offheight)):
        if int(n) > MAX_RENDER_PIXELS:
            raise error(f"<visual> {name} is {int(n)}, expected at most {MAX_RENDER_PIXELS}")
    _check_finite(model, error)
    for fields, lo, hi, unit in FIELD_RANGES:
        for name in fields:
            v = _value(model, name)
            if v is None or v.size == 0:
                continue
            out = np.flatnonzero((v < lo) | (v > hi))
            if out.size:
                raise error(f"{name} = {v.flat[out[0]]:.6g} is outside the physical range "
                            f"[{lo:g}, {hi:g}] {unit}")


def _check_finite(model: mujoco.MjModel, error: Callable[[str], Exception]) -> None:
    for owner, prefix in ((model, ""), (model.opt, "opt."), (model.stat, "stat.")):
        for name in dir(owner):
            if name.startswith("_"):
                continue
            try:
                v = getattr(owner, name)
            except Exception:  # noqa: BLE001 - a property that cannot be read here
                continue
            if isinstance(v, float):
                v = np.asarray(v)
            if isinstance(v, np.ndarray) and v.dtype.kind == "f" and v.size:
                bad = ~np.isfinite(v)
                if bad.any():
                    raise error(f"{prefix}{name} holds {v.flat[np.flatnonzero(bad)[0]]} "
                                "(expected finite numbers: a NaN or infinity in the MJCF?)")
