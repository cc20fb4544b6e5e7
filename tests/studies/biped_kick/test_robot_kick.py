"""The kick on another robot (the OP3): numerical leg IK, the OP3 + ball scene, scaled genes."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.studies.biped_kick.motion import GENE_INDEX
from evomotion.studies.biped_kick.problem import METRICS, KickConfig, KickProblem


@pytest.fixture(scope="module")
def op3() -> KickProblem:
    return KickProblem(KickConfig(robot="op3", aims_deg=(0.0,), roll_after_s=0.4, nthread=1))


def test_nao_keeps_its_closed_form_kick():
    p = KickProblem(KickConfig(nthread=1))
    assert p.kicker.name == "closed_form" and p.metric_names == METRICS
    assert p.robot.name == "nao"


def test_op3_scene_is_read_from_its_model(op3):
    k = op3.kicker
    assert k.name == "numerical" and op3.robot.name == "op3"
    assert k.sole_half == pytest.approx((0.0635, 0.04))  # the OP3's sole box
    assert k.gap_m == pytest.approx(0.02 * 0.0635 / 0.08)  # the NAO's gap, scaled by the sole
    assert 1.0 < k.scale < 1.2  # the OP3's leg is a little longer than the NAO's crouch
    m = op3.model
    ball, floor = m.geom("ball").id, m.geom("floor").id
    assert m.geom_contype[ball] & m.geom_conaffinity[floor]  # the ball lies on the floor
    sole = m.geom("r_sole").id
    assert m.geom_contype[sole] & m.geom_conaffinity[ball]  # and the foot can hit it
    for name in ("l_contact", "r_contact", "l_sole", "r_sole", "l_xaxis", "r_xaxis"):
        assert name in op3.sl
    assert k.decel > 0
    # the ball starts in front of the right toe, on the right sole's centre line
    x, y = op3.ball_xy(k.start[None], np.zeros(1))[0]
    assert x == pytest.approx(k.toe[0] + 0.05 + k.gap_m)
    assert abs(y - k.toe[1]) < 0.01


def test_op3_kick_evaluates_and_moves_the_ball(op3):
    rng = np.random.default_rng(1)
    x = op3.initial_population(2, rng)
    ev = op3.evaluate(x)
    assert np.all(np.isfinite(ev.fitness))
    assert set(ev.metrics) == set(op3.metric_names) and "ik_error_m" in ev.metrics
    assert np.all(ev.metrics["ik_error_m"] < 1e-3)  # the IK reaches the start's foot path
    # the hand-set start (scaled to the OP3) kicks the ball forward
    assert ev.metrics["distance_m"][0] > 0.02
    # the genome bounds are the NAO's, scaled
    i = GENE_INDEX["kick_x_m"]
    assert op3.genome.upper[i] == pytest.approx(0.18 * op3.kicker.scale)


def test_op3_kick_motion_has_op3_joints(op3):
    m = op3.kicker.kick_motion(op3.kicker.start)
    assert m.joints == op3.robot.joints and np.all(np.isfinite(m.values))


def test_robot_without_two_feet_is_refused():
    pytest.importorskip("dm_control")
    with pytest.raises(InputError, match="a kick needs a biped"):
        KickProblem(KickConfig(robot="dm-quadruped", nthread=1))


def test_kick_camera_follows_the_op3_torso(op3):
    """The video's ``kick`` camera follows a torso not named ``torso`` (the OP3's ``body``)."""
    import mujoco

    from evomotion.sim.render import _torso_body

    model = mujoco.MjModel.from_xml_string(op3.kicker.scene_xml, op3.robot.assets)
    assert model.body(_torso_body(model)).name == "body"
    assert model.body_mass[model.body("ball").id] == pytest.approx(0.045)  # the text keeps it
