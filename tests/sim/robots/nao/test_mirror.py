"""The NAO's left-right mirror plays a pose in mirror image: every body of the mirrored pose
sits at the mirror image (y -> -y) of its partner's place, and mirroring twice is the identity."""

from __future__ import annotations

import mujoco
import numpy as np

from evomotion.sim.robots import load_robot, nao
from evomotion.sim.robots.nao.mirror import MIRROR_COLUMNS, mirror_targets


def _partner_body(name: str) -> str:
    side = {"L": "R", "R": "L"}.get(name[:1])
    return side + name[1:] if side and name[1:2].isupper() else name


def test_a_mirrored_pose_is_the_mirror_image():
    r = load_robot("nao")
    m = r.model
    d = mujoco.MjData(m)
    adr = [m.jnt_qposadr[m.joint(j).id] for j in nao.JOINTS]
    lo, hi = m.jnt_range[[m.joint(j).id for j in nao.JOINTS]].T
    rng = np.random.default_rng(0)

    def bodies(q):
        d.qpos[:] = m.qpos0
        d.qpos[adr] = q
        mujoco.mj_kinematics(m, d)
        return d.xpos.copy()

    names = [m.body(b).name for b in range(m.nbody)]
    partner = [names.index(_partner_body(n)) for n in names]
    assert sorted(partner) == list(range(m.nbody)) and partner != list(range(m.nbody))
    for _ in range(20):
        q = rng.uniform(lo, hi)
        x, xm = bodies(q), bodies(mirror_targets(q))
        assert np.abs(xm[partner] - x * [1, -1, 1]).max() < 1e-12


def test_mirroring_twice_is_the_identity_and_pairs_swap():
    q = np.random.default_rng(1).normal(size=(3, len(nao.JOINTS)))
    assert np.array_equal(mirror_targets(mirror_targets(q)), q)
    j = list(nao.JOINTS)
    assert j[MIRROR_COLUMNS[j.index("LHipRoll")]] == "RHipRoll"
    assert MIRROR_COLUMNS[j.index("HeadYaw")] == j.index("HeadYaw")
