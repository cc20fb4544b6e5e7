import json

import pytest

from evomotion.sim.robots.nao.replay import replay, replay_command
from fixture_files import WEBOTS_MOTIONS

FIXTURES = WEBOTS_MOTIONS


@pytest.mark.parametrize("name,sign", [("TurnLeft40", 1), ("TurnLeft60", 1), ("TurnRight40", -1)])
def test_turn_motions_turn_the_right_way(name, sign):
    out = replay(FIXTURES / f"{name}.motion")
    assert not out["fell"]
    assert sign * out["heading_change_rad"] > 0.5  # at least ~29 degrees
    assert abs(out["displacement_m"][0]) < 0.05


def test_side_step_left_moves_left():
    out = replay(FIXTURES / "SideStepLeft.motion")
    assert not out["fell"]
    assert out["displacement_m"][1] > 0.03
    assert abs(out["heading_change_rad"]) < 0.2


def test_hand_wave_keeps_standing():
    out = replay(FIXTURES / "HandWave.motion")
    assert out == {**out, "fell": False, "fall_time_s": None}
    assert max(abs(v) for v in out["displacement_m"]) < 0.02


def test_replay_command_json_only_on_stdout(capsys):
    replay_command(FIXTURES / "HandWave.motion", json_out=True, video=None)
    data = json.loads(capsys.readouterr().out)
    assert set(data) == {"displacement_m", "heading_change_rad", "fell", "fall_time_s"}
    assert len(data["displacement_m"]) == 2


def test_replay_command_human_summary(capsys):
    replay_command(FIXTURES / "TurnRight40.motion", json_out=False, video=None)
    out = capsys.readouterr().out
    assert "TurnRight40.motion" in out and "stayed up" in out


def test_motion_targets_interpolate_and_skip_unset_values():
    import numpy as np

    from evomotion.sim.motion import Motion
    from evomotion.sim.robots import nao
    from evomotion.sim.robots.nao.replay import motion_targets

    m = Motion(("HeadYaw", "LWristYaw"), [0, 100, 200],
               np.array([[0.0, 1.0], [np.nan, 1.0], [0.4, 1.0]]))
    first, ctrl = motion_targets(m, 0.01, 30)
    j = nao.JOINTS.index("HeadYaw")
    assert first[j] == 0.0
    np.testing.assert_allclose(ctrl[[0, 5, 10, 15, 20, 29], j], [0, 0.1, 0.2, 0.3, 0.4, 0.4])
    others = [i for i in range(22) if i != j]
    np.testing.assert_array_equal(ctrl[:, others], np.tile(nao.pose_vector()[others], (30, 1)))
