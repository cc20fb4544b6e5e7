"""sim/stance.py: a biped's stance widened, staggered and lowered from its spec pose, the soles
as flat as in the spec pose, on every bundled biped; one-line errors."""

from __future__ import annotations

import dataclasses

import mujoco
import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.robots import load_robot
from evomotion.sim.stance import stance_pose, with_stance

BIPEDS = ("nao", "op3", "dm-humanoid")


def _soles(robot, pose: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """(position, normal: the site's z axis) of each sole with the robot at rest in ``pose``."""
    m = robot.model
    d = mujoco.MjData(m)
    mujoco.mj_setState(m, d, robot.state_at(pose), mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_kinematics(m, d)
    return [(d.site(robot.sole_site(f)).xpos.copy(),
             d.site(robot.sole_site(f)).xmat.reshape(3, 3)[:, 2].copy()) for f in ("left", "right")]


#: how far a sole's normal may turn (rad) at these sizes: exactly none where only pitch joints
#: lie between the roll joints (the NAO, the OP3); the dm humanoid's hip yaw joint lies between
FLAT_RAD = {"nao": 1.7e-4, "op3": 1.7e-4, "dm-humanoid": 0.03}  # 0.01 deg; 1.7 deg


def _flat(a: np.ndarray, b: np.ndarray, name: str) -> None:
    assert np.arccos(np.clip(a @ b, -1.0, 1.0)) < FLAT_RAD[name], (a, b)


def test_zero_stance_is_the_robot_itself():
    r = load_robot("nao")
    assert with_stance(r) is r
    np.testing.assert_array_equal(stance_pose(r), r.pose)


@pytest.mark.parametrize("name", BIPEDS)
def test_the_stance_keeps_the_soles_flat_and_moves_the_feet_as_named(name):
    r = load_robot(name)
    (l0, lr0), (r0, rr0) = _soles(r, r.pose)
    width = _soles(r, stance_pose(r, width_rad=0.2))
    (lw, lrw), (rw, rrw) = width
    _flat(lrw, lr0, name)  # the soles as flat as in the spec pose
    _flat(rrw, rr0, name)
    assert (lw[1] - rw[1]) > (l0[1] - r0[1]) + 0.02  # wider apart (left is +y)
    (ls, lrs), (rs, rrs) = _soles(r, stance_pose(r, stagger_rad=0.15))
    _flat(lrs, lr0, name)
    _flat(rrs, rr0, name)
    assert (ls[0] - rs[0]) > (l0[0] - r0[0]) + 0.01  # the left foot ahead of the right
    s0 = r.state_at(r.pose)
    crouched = with_stance(r, crouch_rad=0.1)
    (lc, lrc), _ = _soles(r, crouched.pose)
    _flat(lrc, lr0, name)
    assert crouched.state0[3] < s0[3] - 0.003  # the torso (free joint z) lower
    assert crouched.pose is not r.pose and r.pose is load_robot(name).pose


def test_a_stance_beyond_a_joint_range_or_without_gait_roles_is_one_line():
    r = load_robot("nao")
    with pytest.raises(InputError, match=r"problem\.stance.*RAnkleRoll|problem\.stance.*"
                                          "LAnkleRoll"):
        stance_pose(r, width_rad=0.6, where="problem.stance_width_rad")
    bare = dataclasses.replace(r, gait={})
    with pytest.raises(InputError, match="no biped \\[gait\\] roles"):
        stance_pose(bare, width_rad=0.1)
    np.testing.assert_array_equal(stance_pose(bare), r.pose)  # no stance asked: fine


def test_gait_roles_listed_right_leg_first_are_one_line():
    """A spec whose [gait] lists the right leg first would cross the feet: refused."""
    r = load_robot("nao")
    swapped = {role: tuple(reversed(ch)) for role, ch in r.gait.items()}
    bad = dataclasses.replace(r, gait=swapped)
    with pytest.raises(InputError, match="feet together.*left leg's channel first") as e:
        with_stance(bad, 0.3, 0.2, 0.15, where="problem.stance")
    assert str(e.value).startswith("problem.stance: ") and "\n" not in str(e.value)
    assert with_stance(r, 0.3, 0.2, 0.15) is not r  # listed left first: fine


def _at_rest(robot) -> tuple[list, float]:
    """(each sole's (height, normal), the centre of mass ahead of the soles' middle along x)
    of ``robot`` in its initial state."""
    m = robot.model
    d = mujoco.MjData(m)
    mujoco.mj_setState(m, d, robot.state0, mujoco.mjtState.mjSTATE_FULLPHYSICS)
    mujoco.mj_kinematics(m, d)
    mujoco.mj_comPos(m, d)
    sites = [d.site(robot.sole_site(f)) for f in robot.feet]
    soles = [(float(s.xpos[2]), s.xmat.reshape(3, 3)[:, 2].copy()) for s in sites]
    return soles, float(d.subtree_com[0][0] - np.mean([s.xpos[0] for s in sites]))


@pytest.mark.parametrize("name", BIPEDS)
def test_a_lean_pitches_the_torso_forward_with_the_soles_flat_on_the_floor(name):
    """The lean turns the thighs forward and the whole robot back onto flat soles: the centre
    of mass moves forward; the soles stay flat (their mean exactly, each within 0.3 deg on the
    NAO, whose hip roll turns the thigh's pitch axis) and as high as the spec pose's."""
    r = load_robot(name)
    base = with_stance(r, 0.1, 0.1, 0.1)
    leaned = with_stance(r, 0.1, 0.1, 0.1, lean_rad=0.2)
    (soles0, com0), (soles, com) = _at_rest(base), _at_rest(leaned)
    spec_low = min(h for h, _ in _at_rest(r)[0])
    assert min(h for h, _ in soles) == pytest.approx(spec_low, abs=1e-9)
    for (_, n), (_, n0) in zip(soles, soles0, strict=True):
        assert np.arccos(np.clip(n[2], -1.0, 1.0)) < 0.006 + np.arccos(np.clip(n0[2], -1, 1))
    assert com - com0 > 0.01, (com, com0)  # the centre of mass forward (the robot faces +x)
    changed = np.flatnonzero(leaned.pose != base.pose)
    hips = sorted(c for c, _ in r.gait["hip_pitch"])
    assert sorted(changed.tolist()) == hips  # only the hip pitches move
    mean = np.mean([n for _, n in soles], axis=0)
    assert np.arccos(np.clip(mean[2] / np.linalg.norm(mean), -1.0, 1.0)) < 1e-9  # mean flat
