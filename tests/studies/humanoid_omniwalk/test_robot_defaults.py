"""``--robot dm-humanoid`` brings the dm humanoid's own defaults (``Study.robot_defaults``):
the command line its measured runs were made with (docs/humanoid-walk.md), and the user's
``--set``, file and preset still win."""

from __future__ import annotations

import dataclasses

from evomotion.run.config import resolve_config
from evomotion.studies import get_study

# the command line of the measured dm humanoid runs (docs/humanoid-walk.md, "Other bipeds")
MEASURED = ["problem.sway_m=0.008", "problem.sway_phase_rad=1.57",
            "problem.step_height_m=0.005", "problem.perturb=false", "problem.push_max_ns=0",
            "problem.vx_min=0.15", "problem.vx_max=0.3", "problem.vy_max=0.05",
            "problem.yaw_rate_max=0.2", "problem.command_weights=[1, 0, 0, 0, 0]",
            "problem.yaw_share=0", "run.generations=300"]


def test_the_dm_humanoids_defaults_are_its_measured_command_line():
    s = get_study("humanoid-walk")
    robot = "problem.robot='dm-humanoid'"
    by_default = resolve_config(s, overrides=[robot])
    measured = resolve_config(s, overrides=[robot, *MEASURED])
    assert dataclasses.asdict(by_default) == dataclasses.asdict(measured)
    nao = resolve_config(s)  # the NAO and the OP3 keep the study's defaults
    op3 = resolve_config(s, overrides=["problem.robot='op3'"])
    for cfg in (nao, op3):
        assert cfg.problem.perturb and cfg.problem.yaw_share == 0.5
        assert cfg.problem.command_weights != by_default.problem.command_weights
    assert by_default.problem.perturb is False and by_default.problem.yaw_share == 0
    # mirror-symmetric controllers on the NAO only (its mirror capability), named or not
    assert nao.problem.symmetric and resolve_config(
        s, overrides=["problem.robot='nao'"]).problem.symmetric
    assert not op3.problem.symmetric and not by_default.problem.symmetric
    # the narrower yaw-rate kernel, measured on the NAO only
    assert nao.problem.sigma_yaw_rps == 0.15 and op3.problem.sigma_yaw_rps == 0.3


def test_the_users_settings_win_over_the_robots(tmp_path):
    s = get_study("humanoid-walk")
    robot = "problem.robot='dm-humanoid'"
    cfg = resolve_config(s, overrides=[robot, "problem.vx_max=0.25", "run.generations=7"])
    assert cfg.problem.vx_max == 0.25 and cfg.run.generations == 7
    assert cfg.problem.vx_min == 0.15  # the rest stays the robot's
    f = tmp_path / "walk.toml"
    f.write_text('[problem]\nrobot = "dm-humanoid"\nperturb = true\n')
    cfg = resolve_config(s, f)
    assert cfg.problem.perturb is True and cfg.problem.sway_m == 0.008


def test_a_saved_run_config_reruns_as_it_ran(tmp_path):
    """A NAO or dm humanoid run saved before ``problem.symmetric``,
    ``problem.command_weights`` and ``problem.capture_gain`` existed lacks them: ``--config``
    that file runs what it ran (not the robot's defaults now)."""
    from evomotion.run.config import config_to_toml

    s = get_study("humanoid-walk")
    for robot in ("", "dm-humanoid"):
        cfg = resolve_config(s, overrides=[f"problem.robot={robot!r}", "problem.symmetric=false",
                                           "problem.command_weights=[0.3, 0.15, 0.15, 0.3, 0.1]"])
        import tomllib

        import tomli_w

        raw = tomllib.loads(config_to_toml(cfg))
        for key in ("symmetric", "command_weights", "capture_gain"):
            del raw["problem"][key]
        f = tmp_path / f"old-{robot or 'nao'}.toml"
        f.write_text(tomli_w.dumps(raw))
        again = resolve_config(s, f)
        assert again.problem.symmetric is False and again.problem.capture_gain == 0.0
        assert tuple(again.problem.command_weights) == (0.3, 0.15, 0.15, 0.3, 0.1)
        assert again.problem.sway_m == cfg.problem.sway_m  # the rest as saved
