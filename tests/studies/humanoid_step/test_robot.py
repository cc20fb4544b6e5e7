"""humanoid-step on another robot (``--robot``): the GA loop, the run folder, the video."""

from __future__ import annotations

import importlib.util
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study

needs_dm = pytest.mark.skipif(importlib.util.find_spec("dm_control") is None,
                              reason="dm_control is not installed")


def _cli(*args):
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=600)


@needs_dm
def test_step_on_the_dm_control_humanoid(tmp_path):
    s = get_study("humanoid-step")
    over = [*s.smoke, "problem.robot=dm-humanoid", "run.generations=2"]
    res = run_study(s, resolve_config(s, None, over), tmp_path / "r", quiet=True)
    assert res.generation == 2 and np.isfinite(res.best_fitness)
    replay = json.loads((tmp_path / "r" / "best_replay.json").read_text())
    assert replay["robot"] == "dm-humanoid"
    assert replay["torso_height_m"][0] > 1.0  # a 1.3 m tall humanoid, not the NAO
    motion = (tmp_path / "r" / "best.motion").read_text()
    assert "right_hip_y" in motion.splitlines()[0]
    log = (tmp_path / "r" / "log.txt").read_text()
    assert "best step on dm-humanoid" in log
    problem = s.make_problem(resolve_config(s, None, over).problem)
    assert problem.fall_height_m == 0.9 and problem.genome.dim == 12 * 3  # 4 intervals


def test_robot_options_are_checked(tmp_path):
    s = get_study("humanoid-step")
    with pytest.raises(InputError, match="unknown robot 'r2d2'"):
        s.make_problem(resolve_config(s, None, ["problem.robot=r2d2"]).problem)
    r = _cli("run", "functions", "--robot", "nao", "--out", str(tmp_path / "f"))
    assert r.returncode != 0 and "runs only its own robot" in r.stderr
    assert "Traceback" not in r.stderr
    r = _cli("run", "humanoid-step", "--robot", str(tmp_path / "none.toml"), "--out",
             str(tmp_path / "g"))
    assert r.returncode != 0 and "no such robot spec" in r.stderr and "Traceback" not in r.stderr


def test_robot_nao_is_the_default_nao():
    """``--robot nao`` names the default robot: the same problem, bit for bit, for the step,
    the walk and the repertoire; a copy of its spec elsewhere runs the generic robot code."""
    import shutil

    from evomotion.sim.robots import spec_path

    for name in ("humanoid-step", "humanoid-walk-open-loop", "humanoid-repertoire"):
        s = get_study(name)
        base = s.make_problem(resolve_config(s, None, [*s.smoke, "problem.worlds=1"]
                                             if name != "humanoid-repertoire" else
                                             list(s.smoke)).problem)
        assert base.robot.has("leg_ik") and base.robot.name == "nao"
        over = ["problem.robot=nao", *(["problem.worlds=1"]
                                       if name != "humanoid-repertoire" else [])]
        named = s.make_problem(resolve_config(s, None, [*s.smoke, *over]).problem)
        assert type(named) is type(base) and named.robot.has("leg_ik")
        g = np.tile((base.genome.lower + base.genome.upper) / 2, (2, 1))
        np.testing.assert_array_equal(base.evaluate(g).fitness, named.evaluate(g).fitness)
    s = get_study("humanoid-step")
    import tempfile

    with tempfile.TemporaryDirectory() as d:
        copy = Path(d) / "my_nao.toml"
        shutil.copy(spec_path("nao"), copy)
        p = s.make_problem(resolve_config(s, None, [*s.smoke, f"problem.robot={copy}"]).problem)
        assert not p.robot.capabilities and p.robot.name == "nao"
        # perturbed worlds for any robot, pushes scaled by its mass (the copy's: the NAO's)
        w = s.make_problem(resolve_config(s, None, [*s.smoke, f"problem.robot={copy}",
                                                    "problem.worlds=3"]).problem)
        assert len(w.worlds) == 3


def test_physics_json_pins_the_robot_and_a_changed_spec_is_noted(tmp_path):
    import shutil

    from evomotion.run.faults import fault_at
    from evomotion.sim.robots import spec_path

    spec = tmp_path / "op3.toml"
    shutil.copy(spec_path("op3"), spec)
    s = get_study("humanoid-step")
    over = [*s.smoke, f"problem.robot={spec}", "run.generations=1", "run.checkpoint_every=1",
            "run.wall_seconds=0"]
    cfg = resolve_config(s, None, over)
    with fault_at(1, "interrupt"):
        run_study(s, cfg, tmp_path / "r", quiet=True)
    rec = json.loads((tmp_path / "r" / "physics.json").read_text())
    assert rec["robot"] == "op3" and len(rec["robot_spec_sha256"]) == 64
    spec.write_text(spec.read_text().replace("height_m = 0.18", "height_m = 0.170"))
    run_study(s, cfg, tmp_path / "r", quiet=True, resume=True)
    assert "resumed on other physics" in (tmp_path / "r" / "log.txt").read_text()


def test_cli_records_a_spec_path_absolute(tmp_path):
    """``--robot rel/spec.toml`` is recorded absolute: the run resumes from another folder."""
    import shutil

    from evomotion.sim.robots import spec_path

    (tmp_path / "specs").mkdir()
    shutil.copy(spec_path("op3"), tmp_path / "specs" / "op3.toml")
    text = (tmp_path / "specs" / "op3.toml").read_text()
    (tmp_path / "specs" / "op3.toml").write_text(
        text.replace('mjcf = "evomotion:sim/robots/op3/op3.xml"',
                     'mjcf = "evomotion:sim/robots/op3/op3.xml"  # a copy'))
    args = [sys.executable, "-m", "evomotion.cli", "run", "humanoid-step", "--robot",
            "specs/op3.toml", "--out", "r", "-q", "--set", "run.generations=0",
            *[a for kv in get_study("humanoid-step").smoke for a in ("--set", kv)],
            "--set", "run.videos=false"]
    r = subprocess.run(args, cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    cfg = (tmp_path / "r" / "config.toml").read_text()
    assert f'robot = "{(tmp_path / "specs" / "op3.toml").resolve()}"' in cfg
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "resume", str(tmp_path / "r"),
                        "--set", "run.generations=1", "-q"], cwd=tmp_path.parent,
                       capture_output=True, text=True, timeout=300)
    assert r.returncode == 0 and "Traceback" not in r.stderr, r.stderr
