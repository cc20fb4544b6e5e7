"""Standalone check of the ROBOTIS OP3 MJCF (``op3.xml`` next to this file).

Run: ``MUJOCO_GL=osmesa python check_op3.py [--seconds 3] [--image /tmp/op3_stand.png]``
(``--no-image`` skips the render). It prints the model's sizes, total mass and standing
height, holds the "stand" keyframe for a few seconds with the position servos targeting the
keyframe's joint angles, and exits non-zero if the torso sinks below 70 % of its start height,
tilts more than 20 degrees, drifts more than 2 cm, or a sole sits not 0.5 mm above the floor.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

os.environ.setdefault("MUJOCO_GL", "osmesa")  # before mujoco is imported: it reads it then

import mujoco  # noqa: E402
import numpy as np  # noqa: E402

HERE = Path(__file__).resolve().parent
MODEL = HERE / "op3.xml"
PUBLISHED_MASS_KG = 3.5  # ROBOTIS e-Manual, OP3 specifications
URDF_MASS_KG = 3.14747  # sum of the masses in op3_description/urdf/robotis_op3.inertia.xacro
CAD_MASS_KG = 3.1408  # "all" in op3_description/doc/OP3 mass property.docx


def lowest_z(model: mujoco.MjModel, data: mujoco.MjData, g: int) -> float:
    """Lowest world z of the box geom ``g`` (its 8 corners)."""
    half = model.geom_size[g]
    corners = np.array([[sx, sy, sz] for sx in (-1, 1) for sy in (-1, 1)
                        for sz in (-1, 1)]) * half
    world = data.geom_xpos[g] + corners @ data.geom_xmat[g].reshape(3, 3).T
    return float(world[:, 2].min())


def tilt_deg(quat: np.ndarray) -> float:
    """Angle between the torso's z axis and the world's vertical."""
    mat = np.empty(9)
    mujoco.mju_quat2Mat(mat, quat)
    return float(np.degrees(np.arccos(np.clip(mat[8], -1.0, 1.0))))


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=3.0)
    ap.add_argument("--image", default="/tmp/op3_stand.png")
    ap.add_argument("--no-image", action="store_true")
    args = ap.parse_args()

    model = mujoco.MjModel.from_xml_path(str(MODEL))
    data = mujoco.MjData(model)
    failures: list[str] = []

    torso = model.body("body").id
    mass = float(model.body_subtreemass[0])
    print(f"model: {MODEL.name}  nq={model.nq} nv={model.nv} nu={model.nu} "
          f"njnt={model.njnt} nbody={model.nbody} ngeom={model.ngeom}")
    opt = model.opt
    print(f"timestep={opt.timestep}  integrator={mujoco.mjtIntegrator(opt.integrator).name}"
          f"  solver={mujoco.mjtSolver(opt.solver).name}  cone={mujoco.mjtCone(opt.cone).name}")
    print(f"total mass: {mass:.5f} kg (URDF sum {URDF_MASS_KG} kg; ROBOTIS CAD {CAD_MASS_KG} kg;"
          f" e-Manual {PUBLISHED_MASS_KG} kg)")
    if abs(mass - URDF_MASS_KG) > 1e-4:
        failures.append(f"total mass {mass:.5f} != URDF sum {URDF_MASS_KG}")
    if (model.nq, model.nv, model.nu) != (27, 26, 20):
        failures.append(f"nq/nv/nu = {model.nq}/{model.nv}/{model.nu}, expected 27/26/20")

    # every actuator is a position servo named like its joint, ctrlrange = joint range
    for a in range(model.nu):
        j = int(model.actuator_trnid[a, 0])
        if model.actuator(a).name != model.joint(j).name:
            failures.append(f"actuator {model.actuator(a).name} drives {model.joint(j).name}")
        if not np.allclose(model.actuator_ctrlrange[a], model.jnt_range[j]):
            failures.append(f"actuator {model.actuator(a).name}: ctrlrange != joint range")

    # zero pose (straight legs, arms sideways): height of the head's top
    mujoco.mj_forward(model, data)
    head = model.geom("head").id
    top0 = data.geom_xpos[head][2] + model.geom_size[head][2]
    print(f"zero pose: torso origin {data.xpos[torso][2]:.4f} m, head top {top0:.4f} m "
          "(e-Manual height 0.510 m)")

    # stand keyframe
    key = model.key("stand").id
    mujoco.mj_resetDataKeyframe(model, data, key)
    targets = np.array([data.qpos[model.jnt_qposadr[model.actuator_trnid[a, 0]]]
                        for a in range(model.nu)])
    if not np.allclose(targets, model.key_ctrl[key]):
        failures.append("keyframe ctrl differs from the keyframe's joint angles")
    data.ctrl[:] = targets
    mujoco.mj_forward(model, data)
    soles = {n: lowest_z(model, data, model.geom(n).id) for n in ("l_sole", "r_sole")}
    top = data.geom_xpos[head][2] + model.geom_size[head][2]
    z0 = float(data.xpos[torso][2])
    sole_xy0 = {n: data.geom_xpos[model.geom(n).id][:2].copy() for n in ("l_sole", "r_sole")}
    xy0 = data.xpos[torso][:2].copy()
    com = data.subtree_com[torso]
    print(f"stand: torso origin {z0:.4f} m, head top (standing height) {top:.4f} m, "
          f"CoM ({com[0]:+.4f}, {com[1]:+.4f}, {com[2]:.4f}) m")
    print("stand: sole undersides " + ", ".join(f"{n} {1000 * z:.3f} mm" for n, z in soles.items())
          + f"; ncon={data.ncon}")
    for n, z in soles.items():
        if abs(z - 0.0005) > 2e-5:
            failures.append(f"{n} underside at {1000 * z:.3f} mm, not 0.5 mm")
    for n in ("l_sole", "r_sole"):
        sx, sy, sz = 2 * model.geom_size[model.geom(n).id]
        print(f"{n}: {1000 * sx:.1f} x {1000 * sy:.1f} x {1000 * sz:.1f} mm, "
              f"friction {model.geom_friction[model.geom(n).id][0]}")

    # hold the pose: mujoco.rollout from the keyframe state, constant ctrl
    nstep = int(round(args.seconds / model.opt.timestep))
    spec = mujoco.mjtState.mjSTATE_FULLPHYSICS
    state0 = np.empty(mujoco.mj_stateSize(model, spec))
    mujoco.mj_getState(model, data, state0, spec)
    ctrl = np.tile(targets, (nstep, 1))
    from mujoco import rollout

    states, _ = rollout.rollout(model, data, state0[None], ctrl[None])
    states = states[0]
    # FULLPHYSICS state: time, qpos, qvel, act, ...
    qpos = states[:, 1:1 + model.nq]
    z = qpos[:, 2]
    tilt = np.array([tilt_deg(q[3:7]) for q in qpos])
    drift = np.linalg.norm(qpos[:, :2] - xy0, axis=1)
    joint_err = np.abs(qpos[-1, 7:] - model.key_qpos[key, 7:])
    print(f"after {args.seconds:.1f} s ({nstep} steps): torso height {z[-1]:.4f} m "
          f"({100 * z[-1] / z0:.1f} % of start; min {z.min():.4f}), tilt {tilt[-1]:.2f} deg "
          f"(max {tilt.max():.2f}), horizontal drift {1000 * drift[-1]:.2f} mm "
          f"(max {1000 * drift.max():.2f}); max joint error {joint_err.max():.4f} rad")
    # did the soles slide? (the torso's drift above comes from the servos' compliance)
    probe = mujoco.MjData(model)
    probe.qpos[:] = qpos[-1]
    mujoco.mj_kinematics(model, probe)
    slip = {n: 1000 * float(np.linalg.norm(probe.geom_xpos[model.geom(n).id][:2] - xy))
            for n, xy in sole_xy0.items()}
    print("sole slip: " + ", ".join(f"{n} {v:.2f} mm" for n, v in slip.items()))
    if z.min() < 0.7 * z0:
        failures.append(f"torso fell to {z.min():.4f} m")
    if tilt.max() > 20:
        failures.append(f"torso tilted {tilt.max():.1f} deg")
    if drift.max() > 0.02:
        failures.append(f"torso drifted {1000 * drift.max():.1f} mm")

    if not args.no_image:
        mujoco.mj_resetDataKeyframe(model, data, key)
        mujoco.mj_forward(model, data)
        cam = mujoco.MjvCamera()
        cam.type = mujoco.mjtCamera.mjCAMERA_FREE
        cam.lookat[:] = data.xpos[torso] + np.array([0.0, 0.0, -0.03])
        cam.distance = 0.95
        cam.azimuth = 150.0  # from the front (+x), the robot's right side
        cam.elevation = -12.0
        renderer = mujoco.Renderer(model, 480, 360)  # height, width
        try:
            renderer.update_scene(data, camera=cam)
            pixels = renderer.render()
        finally:
            renderer.close()
        _save_png(args.image, pixels)
        print(f"image: {args.image} ({pixels.shape[1]}x{pixels.shape[0]})")

    if failures:
        print("FAIL:\n  " + "\n  ".join(failures))
        return 1
    print("OK")
    return 0


def _save_png(path: str, pixels: np.ndarray) -> None:
    """``pixels`` as a PNG at ``path``, written atomically (:mod:`evomotion.outfile`)."""
    from evomotion.outfile import atomic_output

    with atomic_output(path, "image", suffix=".tmp.png") as tmp:
        _write_png(tmp, pixels)


def _write_png(path: Path, pixels: np.ndarray) -> None:
    try:
        from PIL import Image

        Image.fromarray(pixels).save(path)
    except ImportError:  # minimal PNG writer (zlib), no extra dependency
        import struct
        import zlib

        h, w, _ = pixels.shape
        raw = b"".join(b"\x00" + pixels[r].tobytes() for r in range(h))

        def chunk(tag: bytes, body: bytes) -> bytes:
            return (struct.pack(">I", len(body)) + tag + body
                    + struct.pack(">I", zlib.crc32(tag + body) & 0xFFFFFFFF))

        header = struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)
        path.write_bytes(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header)
                         + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b""))


if __name__ == "__main__":
    sys.exit(main())
