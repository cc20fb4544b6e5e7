"""Leg kinematics (closed form vs. round trip and vs. MuJoCo) and the model's basics."""

import math

import mujoco
import numpy as np
import pytest

from evomotion.sim.quadruped import QuadrupedSpec, build_model, leg_fk, leg_ik, legs_fk, legs_ik
from evomotion.sim.quadruped.ik import reachable, sector_point_m
from evomotion.sim.quadruped.model import LEG_NAMES, TORSO, model_xml

SPEC = QuadrupedSpec()


@pytest.mark.parametrize("leg", range(4))
def test_fk_inverts_ik_over_the_whole_sector(leg: int) -> None:
    hw = SPEC.sector_half_width
    length, offset, lift = np.meshgrid(np.linspace(SPEC.l_min, SPEC.l_max, 31),
                                       np.linspace(-hw, hw, 31),
                                       np.linspace(0.0, SPEC.max_lift_m, 5), indexing="ij")
    p = sector_point_m(SPEC, leg, length, offset, lift)
    assert reachable(SPEC, leg, p).all()
    q = leg_ik(SPEC, leg, p)
    np.testing.assert_allclose(leg_fk(SPEC, leg, q), p, rtol=0, atol=1e-9)
    # the knee bends upwards and the yaw stays inside the joint's range
    assert (q[..., 2] > 0).all() and (np.abs(q[..., 0]) <= hw + 1e-9).all()


def test_fk_agrees_with_mujoco_kinematics() -> None:
    model = build_model(SPEC)
    data = mujoco.MjData(model)
    rng = np.random.default_rng(3)
    for _ in range(20):
        data.qpos[:3] = rng.uniform(-1, 1, 3)
        quat = rng.normal(size=4)
        data.qpos[3:7] = quat / np.linalg.norm(quat)
        data.qpos[7:] = rng.uniform(-1.2, 1.2, 12)
        mujoco.mj_kinematics(model, data)
        rot = data.body(TORSO).xmat.reshape(3, 3)
        feet = legs_fk(SPEC, data.qpos[7:])
        for i, name in enumerate(LEG_NAMES):
            rel = rot.T @ (data.site(f"{name}_foot").xpos - data.body(TORSO).xpos)
            np.testing.assert_allclose(feet[i], rel, atol=1e-12)
            rel_geom = rot.T @ (data.geom(f"{name}_foot").xpos - data.body(TORSO).xpos)
            np.testing.assert_allclose(feet[i], rel_geom, atol=1e-12)
    np.testing.assert_allclose(legs_ik(SPEC, legs_fk(SPEC, legs_ik(SPEC, feet))),
                               legs_ik(SPEC, feet), atol=1e-9)


def test_ik_clamps_out_of_reach_and_passes_nan() -> None:
    far = np.array([-1.0, 0.15, -0.1])  # far beyond the front-left leg's reach
    q = leg_ik(SPEC, 0, far)
    assert np.isfinite(q).all() and not reachable(SPEC, 0, far)
    assert np.isnan(leg_ik(SPEC, 0, np.array([np.nan, 0.0, -0.1]))).any()


def test_spec_rejects_unreachable_sector() -> None:
    with pytest.raises(ValueError, match="reach"):
        QuadrupedSpec(thigh_m=0.08, shank_m=0.08)


def test_model_structure_and_collisions() -> None:
    model = build_model(SPEC)
    assert (model.nq, model.nv, model.nu) == (19, 18, 12)
    assert model.opt.cone == mujoco.mjtCone.mjCONE_ELLIPTIC
    assert math.isclose(model.opt.timestep, SPEC.timestep)
    torso = model.body(TORSO).id
    assert model.body_mass[torso] > 8 * (model.body_mass.sum() - model.body_mass[torso])
    floor, box = model.geom("floor").id, model.geom(TORSO).id

    def collide(g1: int, g2: int) -> bool:
        return bool(model.geom_contype[g1] & model.geom_conaffinity[g2]
                    or model.geom_contype[g2] & model.geom_conaffinity[g1])

    assert collide(floor, box)
    legs = [g for g in range(model.ngeom) if model.geom_bodyid[g] != torso and g != floor
            and model.geom_contype[g]]
    assert legs and all(collide(floor, g) for g in legs)
    assert not any(collide(box, g) for g in legs)
    assert not any(collide(g, h) for g in legs for h in legs)
    assert mujoco.MjModel.from_xml_string(model_xml(SPEC)).nsensordata == model.nsensordata
