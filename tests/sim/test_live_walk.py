"""A walk controller driven live (the studio's drive view; issue 35), with the shipped walk
controller of the kick study."""

from __future__ import annotations

from importlib.resources import files

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.sim.live_walk import LiveWalk

SHIPPED = files("evomotion.studies.biped_kick") / "default_walk"


def test_a_live_forward_command_walks_forward_and_a_turn_turns():
    w = LiveWalk(SHIPPED)
    assert set(w.command_ranges) == {"vx", "vy", "yaw_rate"}
    for _ in range(50):
        w.advance([0.3, 0.0, 0.0], 0.06)
    s = w.status()
    assert not s["fell"] and s["x_m"] > 0.4 and s["command_vx"] == pytest.approx(0.3)
    for _ in range(40):
        w.advance([0.0, 0.0, 1.0], 0.06)
    assert not w.status()["fell"] and w.status()["heading_deg"] > 45


def test_commands_are_clipped_to_the_ranges_pushes_count_and_reset_starts_again():
    w = LiveWalk(SHIPPED)
    w.advance([5.0, 0.0, 0.0], 1.0)
    assert w.player.command[0] <= w.command_ranges["vx"][1] + 1e-12
    v0 = w.data.qvel[:3].copy()
    w.push(5.0, 90.0)
    w.advance([0.0, 0.0, 0.0], 0.02)
    dv = w.data.qvel[1] - v0[1]
    assert dv > 0.5 * 5.0 / w.mass_kg  # the impulse moved the torso sideways
    w.reset()
    assert w.data.time == 0.0 and not w.fell and np.allclose(w.status()["x_m"], 0.0)
    for bad in ((-1.0, 0.0), (25.0, 0.0), (1.0, float("nan"))):
        with pytest.raises(InputError):
            w.push(*bad)


def test_another_robots_controller_walks_that_robot(tmp_path):
    """An OP3 walk run's controller (a one-generation run) is driven on the OP3 (the robot the
    studio reads from the run's config: studio/views.robot_of), framed by its size; an unknown
    robot is one line."""
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study

    s = get_study("humanoid-walk")
    out = tmp_path / "op3"
    run_study(s, resolve_config(s, None, ["problem.robot='op3'", *s.smoke,
                                          "run.generations=1", "run.videos=false"]),
              out, quiet=True)
    walk = LiveWalk(out, "op3")
    assert walk.robot.name == "op3" and 0.2 < walk.height_m < 0.3
    assert walk.advance(np.array([0.1, 0.0, 0.0]), 0.5) == 25 and not walk.fell
    with pytest.raises(InputError, match="r2d2") as e:
        LiveWalk(out, "r2d2")
    assert "\n" not in str(e.value)
    with pytest.raises(InputError, match="not in the simulated model"):
        LiveWalk(out, "nao")  # the OP3's joints are not the NAO's
