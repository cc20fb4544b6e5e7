"""humanoid-walk: the controller starts as the walk engine, evaluations are independent of
their neighbours, the run's files, compare, one-line errors."""

from __future__ import annotations

import json
import re

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study
from evomotion.studies.humanoid_omniwalk.compare import compare, compare_command
from evomotion.studies.humanoid_omniwalk.omni_gait import targets
from evomotion.studies.humanoid_omniwalk.problem import OmniWalkConfig, OmniWalkProblem
from evomotion.studies.policy_search import policy_rows

TINY = ("problem.duration_s=1.0", "problem.eval_episodes=1", "problem.episodes=1",
        "problem.threads=1", "algorithm.pop_size=4", "algorithm.top_directions=0",
        "run.generations=1", "run.videos=false", "run.seed=3")


@pytest.fixture(scope="module")
def problem():
    return OmniWalkProblem(OmniWalkConfig(duration_s=1.5, threads=1))


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("omniwalk") / "run"
    s = get_study("humanoid-walk")
    run_study(s, resolve_config(s, None, list(TINY)), out, quiet=True)
    return out


def test_the_search_starts_at_the_walk_engine(problem):
    """The fitted tape (feedback 0) reproduces the engine's targets for commands off the fit
    grid within 0.03 rad (rms per joint), whatever the normaliser."""
    ctl = problem.ctl
    x0 = problem.initial_population(None, np.random.default_rng(0))[0]
    rng = np.random.default_rng(1)
    n = 300
    cmd = rng.uniform([-0.2, -0.2, -1.2], [0.45, 0.2, 1.2], (n, 3))
    t = rng.uniform(0, 5, n)
    phi = 2 * np.pi * t / ctl.gait.period_s
    obs = rng.normal(size=(n, problem.obs_dim))
    names = list(problem.obs_names)
    obs[:, names.index("phase:sin")], obs[:, names.index("phase:cos")] = np.sin(phi), np.cos(phi)
    for i in range(3):
        obs[:, names.index(f"command:{i}")] = cmd[:, i]
    got = problem.policy.act(np.tile(x0, (n, 1)), obs, rng.normal(size=problem.obs_dim),
                             np.ones(problem.obs_dim))
    want = targets(ctl.gait, t / ctl.gait.period_s, cmd)[:, ctl.columns] - \
        ctl.nominal[ctl.columns]
    assert np.sqrt(np.mean((got - want) ** 2, axis=0)).max() < 0.03


def test_evaluation_rows_are_independent_of_their_neighbours(problem):
    x0 = problem.initial_population(None, np.random.default_rng(0))
    g = x0 + 0.002 * np.random.default_rng(2).standard_normal((3, problem.genome.dim))
    rows = policy_rows(g, np.zeros(problem.obs_dim), np.ones(problem.obs_dim), 11, 2)
    ev = problem.evaluate(rows)
    np.testing.assert_array_equal(problem.evaluate(rows[1:2]).fitness, ev.fitness[1:2])
    assert set(ev.metrics) >= set(problem.metric_names)
    assert np.all(ev.metrics["power_w"] > 0) and np.all(ev.metrics["speed_excess"] >= 0)


def _walk_and_fold(problem) -> np.ndarray:
    """Two controllers: the engine's walk and one that folds the knees (it falls)."""
    x0 = problem.initial_population(None, np.random.default_rng(0))[0]
    (C, _), (K, _) = problem.policy.unflatten(x0)
    names = [problem.robot.model.actuator(int(c)).name for c in problem.sim.columns]
    C = C.copy()
    C[[names.index("LKneePitch"), names.index("RKneePitch")], 0] += 1.5
    return np.stack([x0, problem.policy.flatten([(C, None), (K, None)])])


def test_a_fall_scores_below_walking_on(problem):
    """The engine's walk beside a controller that folds the knees: it falls and scores less."""
    m, res, _ = problem.play(_walk_and_fold(problem), np.zeros((2, problem.obs_dim)),
                             np.ones((2, problem.obs_dim)), np.array([5, 5]))
    assert res.fell[1] and m["return"][1] < m["return"][0]


def test_the_fall_weight_costs_a_fallen_episode_exactly_that(problem):
    """``fall_weight`` lowers the score of an episode that fell by itself, and nothing else."""
    import dataclasses

    P = _walk_and_fold(problem)
    M, S = np.zeros((2, problem.obs_dim)), np.ones((2, problem.obs_dim))
    heavy = OmniWalkProblem(dataclasses.replace(problem.cfg, fall_weight=0.5))
    m0, res, _ = problem.play(P, M, S, np.array([5, 5]))
    m1, _, _ = heavy.play(P, M, S, np.array([5, 5]))
    assert res.fell.tolist() == [False, True]
    np.testing.assert_allclose(m1["return"], m0["return"] - 0.5 * res.fell, rtol=0, atol=1e-12)
    with pytest.raises(InputError, match="problem.fall_weight"):
        OmniWalkConfig(fall_weight=-1.0).validate()


def test_run_writes_the_controller_and_its_description(run_dir, problem):
    for name in ("policy.npz", "policy.py", "policy.json", "best.json", "stats.csv"):
        assert (run_dir / name).is_file(), name
    info = json.loads((run_dir / "policy.json").read_text())
    assert info["observations"] == list(problem.obs_names)
    assert len(info["joints"]) == problem.act_dim == 15
    assert info["followers"] == {"RHipYawPitch": "LHipYawPitch"}
    assert info["phase_period_s"] == problem.ctl.gait.period_s
    record = json.loads((run_dir / "naoqi" / "policy.json").read_text())
    assert (run_dir / "naoqi" / "policy_runner.py").is_file()
    log = (run_dir / "log.txt").read_text()
    assert "humanoid-walk: best centre score" in log
    assert "evomotion humanoid-walk compare RUN measures it" in log
    assert record["command_ramp_s"] == 0.5 and record["joints"] == info["joints"]
    # the NAO's default controller has capture steps: recorded, and their file exported
    assert info["layers"]["capture_step"]["gain"] == record["capture_step"]["gain"] == 1.0
    assert (run_dir / "capture_step.py").is_file()
    assert (run_dir / "naoqi" / "capture_step.py").is_file()
    if (run_dir / "controller.onnx").is_file():  # with the onnx extra
        assert "policy.onnx, capture_step.py, controller.onnx; evomotion" in log


def test_compare_prints_both_controllers_and_the_top_speeds(run_dir):
    text = compare_command(run_dir, worlds=2, duration_s=1.0)
    # the NAO's default has capture steps on top (problem.capture_gain 1)
    assert "| evolved controller |" in text and "| walk engine (the start) + capture step" in text
    assert "| forward [0.45, 0.0, 0.0] |" in text
    assert "| stand [0.0, 0.0, 0.0] | vx " in text and " cm/s, " in text  # the creep
    res = json.loads(compare_command(run_dir, worlds=2, duration_s=1.0, json_out=True))
    assert 0 <= res["controller"]["survival"] <= 1
    assert set(res["engine"]["top_speeds"]) == {"forward", "backward", "left", "right",
                                                "turn_left", "turn_right", "stand"}


def test_bad_input_is_one_line(run_dir, tmp_path):
    with pytest.raises(InputError, match="--worlds"):
        compare(run_dir, worlds=0)
    with pytest.raises(InputError, match="--duration"):
        compare(run_dir, worlds=1, duration_s=float("nan"))
    with pytest.raises(InputError, match="expected a humanoid-walk run folder"):
        compare(tmp_path / "nothing")
    with pytest.raises(InputError, match="control_period_s"):
        OmniWalkProblem(OmniWalkConfig(control_period_s=0.01, threads=1))
    with pytest.raises(InputError, match="hold_max_s"):
        OmniWalkConfig(hold_min_s=3.0, hold_max_s=2.0).validate()


def test_the_engine_walks_and_turns_the_commanded_way():
    """The fitted engine (the search's start) in the nominal world: each command alone moves
    the torso its way (the yaw measured unwrapped: a turn past 180 degrees once read as the
    opposite turn)."""
    import math

    from evomotion.studies.humanoid_omniwalk.commands import tracking

    p = OmniWalkProblem(OmniWalkConfig(duration_s=4.0, threads=1, perturb=False,
                                       push_max_ns=0.0))
    x0 = p.ctl.initial_params()
    C = math.ceil(p.nstep / p.control_steps)
    ramp = np.clip(np.arange(C) * 0.02 / 0.5, 0, 1)[None, :, None]
    cmds = np.array([[0.25, 0, 0], [-0.15, 0, 0], [0, 0.1, 0], [0, -0.1, 0], [0, 0, 1.0],
                     [0, 0, -1.0]])
    P = np.repeat(x0[None], len(cmds), axis=0)
    res = p.sim.run(lambda r, o: p.policy.act(P[r], o, np.zeros(p.obs_dim),
                                              np.ones(p.obs_dim)),
                    len(cmds), p.nstep, commands=cmds[:, None] * ramp,
                    initial_state=p.ctl.state0)
    tr = tracking(res.torso, cmds[:, None] * ramp, p.ctl.window, 0.02)
    walked = np.stack([tr.vx, tr.vy, tr.yaw_rate], -1)[:, -75:].mean(axis=1)
    assert not res.fell.any()
    for i, c in enumerate(cmds):
        axis = int(np.flatnonzero(c)[0])
        assert np.sign(walked[i, axis]) == np.sign(c[axis]) and \
            abs(walked[i, axis]) > 0.4 * abs(c[axis]), (c, walked[i])


def _cli(*args: str):
    import subprocess
    import sys

    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=180)


def test_replay_with_a_command_a_command_file_and_bad_ones(run_dir, tmp_path):
    r = _cli("replay", str(run_dir), "--command", "0.2,0,0", "--duration", "1.5", "--json")
    assert r.returncode == 0, r.stderr
    out = json.loads(r.stdout)
    assert out["command"] == "0.2,0,0" and out["duration_s"] == 1.5
    f = tmp_path / "cmds.txt"
    f.write_text("# t vx vy w\n0, 0.1, 0, 0\n0.8 0 0 0.5\n")
    r = _cli("replay", str(run_dir), "--command", str(f), "--duration", "1.5", "--stress", "2")
    assert r.returncode == 0, r.stderr
    assert "walk controller of run" in r.stdout and "2 perturbed worlds" in r.stdout
    bad = tmp_path / "bad.txt"
    for text, message in (("0 1 2\n", "bad.txt:1: expected"), ("1 0 0 0\n0.5 0 0 0\n",
                                                                "bad.txt:2: times")):
        bad.write_text(text)
        r = _cli("replay", str(run_dir), "--command", str(bad))
        assert r.returncode != 0 and "Traceback" not in r.stderr and message in r.stderr
    r = _cli("replay", str(run_dir), "--command", "0.1,nan,0")
    assert r.returncode != 0 and len(r.stderr.strip().splitlines()) == 1


def test_ramped_commands_match_training_schedules():
    from evomotion.studies.humanoid_omniwalk.replay import ramped

    t = np.arange(0, 4, 0.02)
    c = ramped(np.array([0.0, 2.0]), np.array([[0.3, 0, 0], [0, 0, 1.0]]), t, 0.5)
    assert np.allclose(c[0], 0) and np.allclose(c[25:100], [0.3, 0, 0])
    assert np.allclose(c[100], [0.3, 0, 0]) and np.allclose(c[-1], [0, 0, 1.0])
    assert np.abs(np.diff(c, axis=0)).max() <= 1.0 * 0.02 / 0.5 + 1e-12


def test_the_policy_player_sends_the_training_loops_targets(run_dir, problem, tmp_path):
    """sim.policy_player (the exported files played in any model, as biped-kick play does)
    sends the targets the training's closed loop sends, stepping its own MjData: the same
    observations from the same state and command, within 1e-6 rad over 1 s of walking. The
    run's policy with every parameter jittered, so that every observation column matters."""
    import shutil

    import mujoco

    from evomotion.core.policies.export import read_policy_npz, write_policy_npz
    from evomotion.sim.policy_player import PolicyPlayer
    from evomotion.sim.state import STATE_SPEC

    run = read_policy_npz(run_dir / "policy.npz")
    jitter = 0.01 * np.random.default_rng(5).standard_normal(run.params.shape)
    write_policy_npz(tmp_path / "policy.npz", run.spec, run.params + jitter, run.obs_mean,
                     run.obs_std)
    shutil.copy(run_dir / "policy.json", tmp_path / "policy.json")
    run_dir = tmp_path
    pol = read_policy_npz(run_dir / "policy.npz")
    model = problem.robot.model
    sim = problem.sim
    C = 50  # 1 s of 20 ms control steps
    cmd = np.linspace(0, 1, C)[:, None] * np.array([0.2, 0.05, 0.3])  # slower than the ramp
    res = sim.run(lambda rows, obs: pol.spec.act(np.tile(pol.params, (len(rows), 1)), obs,
                                                 pol.obs_mean, pol.obs_std),
                  1, C * sim.k, commands=cmd[None], initial_state=problem.ctl.state0,
                  record_targets=True)
    assert not res.fell[0]
    player = PolicyPlayer(run_dir, model, {"left": "left_floor", "right": "right_floor"})
    d = mujoco.MjData(model)
    mujoco.mj_setState(model, d, problem.ctl.state0, STATE_SPEC)
    mujoco.mj_forward(model, d)
    player.start(d)
    sent = []
    for c in range(C):
        ctrl = player.targets(d, cmd[c])
        sent.append(ctrl[player.columns])
        d.ctrl[:] = ctrl
        for _ in range(player.control_steps):
            mujoco.mj_step(model, d)
    assert np.abs(np.array(sent) - res.targets[0]).max() < 1e-6
    assert np.array_equal(player.columns, sim.columns)


@pytest.mark.parametrize("key, value, message", [
    ("followers", "abc", "key 'followers': an object of actuator names"),
    ("followers", 5, "key 'followers': an object of actuator names"),
    ("followers", {"RHipYawPitch": 3}, "key 'followers': an object of actuator names"),
    ("control_period_s", 1e300, "key 'control_period_s': a whole number (1 to 1000)"),
    ("control_period_s", 1e-300, "key 'control_period_s': a whole number (1 to 1000)"),
    ("control_period_s", 0.021, "key 'control_period_s': a whole number (1 to 1000)"),
])
def test_the_policy_player_refuses_a_bad_policy_json(run_dir, problem, tmp_path, key, value,
                                                      message):
    """A hand-edited policy.json the player cannot follow is one line naming the key, not a
    traceback (followers that are no object) or a hang (a control period of 1e300 s)."""
    import shutil

    from evomotion.sim.policy_player import PolicyPlayer

    shutil.copy(run_dir / "policy.npz", tmp_path / "policy.npz")
    info = json.loads((run_dir / "policy.json").read_text())
    info[key] = value
    (tmp_path / "policy.json").write_text(json.dumps(info))
    with pytest.raises(InputError, match=re.escape(message)):
        PolicyPlayer(tmp_path, problem.robot.model, {"left": "left_floor",
                                                     "right": "right_floor"})


def test_command_feedback_starts_where_it_is_set():
    """With command feedback the search starts with G = 0 but for vx's gain on the normalised
    gravity:x (``problem.command_feedback_start``); the tape and K are the plain start's; a
    start out of range or without command feedback's layer is refused in one line."""
    plain = OmniWalkProblem(OmniWalkConfig(duration_s=1.0, threads=1, command_feedback=False))
    fed = OmniWalkProblem(OmniWalkConfig(duration_s=1.0, threads=1, command_feedback=True,
                                         command_feedback_start=0.1))
    new = resolve_config(get_study("humanoid-walk"), None, []).problem  # a new run's
    assert new.command_feedback and new.command_feedback_start == 0.1
    assert not OmniWalkConfig().command_feedback  # what a run folder without the key meant
    (C, _), (K, _), (G, _) = fed.policy.unflatten(fed.ctl.initial_params())
    (C0, _), (K0, _) = plain.policy.unflatten(plain.ctl.initial_params())
    assert np.array_equal(C, C0) and np.array_equal(K, K0)
    names = [fed.obs_names[k] for k in fed.policy.feedback_columns]
    assert G.shape == (3, len(names)) and np.count_nonzero(G) == 1
    assert G[0, names.index("gravity:x")] == 0.1
    with pytest.raises(InputError, match="command_feedback_start"):
        OmniWalkConfig(command_feedback_start=5.0).validate()
    with pytest.raises(InputError, match="command_feedback"):
        OmniWalkConfig(command_feedback=1).validate()


def test_a_forward_only_run_trains_on_forward_commands_and_names_its_slowest_test(tmp_path):
    """``problem.command_weights = [1, 0, 0, 0, 0]`` with ``vx_min > 0`` (how the dm humanoid
    learns to walk forward): every training command is forward, and the top-speed test at
    ``vx_min`` is named ``forward_min``, not ``backward``."""
    from evomotion.studies.humanoid_omniwalk.commands import schedules
    from evomotion.studies.humanoid_omniwalk.compare import top_speeds

    sets = [*TINY, "problem.command_weights=[1, 0, 0, 0, 0]", "problem.vx_min=0.1"]
    s = get_study("humanoid-walk")
    run_study(s, resolve_config(s, None, sets), tmp_path / "run", quiet=True)
    cfg = OmniWalkConfig(duration_s=1.0, threads=1, command_weights=(1.0, 0, 0, 0, 0),
                         vx_min=0.1)
    p = OmniWalkProblem(cfg)
    cmds = schedules(cfg.commands(), np.arange(30), np.arange(200) * 0.02)
    assert np.all(cmds[..., 1:] == 0) and np.all(cmds[:, 25:, 0] >= 0.1 - 1e-12)
    speeds = top_speeds(p, p.ctl.initial_params(), np.zeros(p.obs_dim), np.ones(p.obs_dim))
    assert "forward_min" in speeds and "backward" not in speeds
    assert speeds["forward_min"]["command"] == [0.1, 0.0, 0.0]


def test_physics_json_records_the_host_and_a_resume_on_another_is_noted(tmp_path):
    """A seed's bits hold on hosts whose numpy, SIMD features and BLAS kernels agree
    (sim/cpu_platform.py): the run records them; resumed where OpenBLAS chose other kernels
    (another process told ``OPENBLAS_CORETYPE``), the log says the result is not
    bit-identical; a folder from before the keys were recorded resumes without a note."""
    import os
    import platform
    import subprocess
    import sys

    from evomotion.sim.cpu_platform import cpu_platform

    here = cpu_platform()["blas"]
    if not (sys.platform.startswith("linux") and platform.machine() == "x86_64") or \
            here.endswith((" ?", " Nehalem")):
        pytest.skip(f"needs an x86 OpenBLAS whose kernels can be told: {here}")
    run = tmp_path / "r"
    sets = [a for kv in (*TINY, "run.checkpoint_every=1") for a in ("--set", kv)]
    subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-walk", "--out",
                    str(run), "-q", *sets], check=True, timeout=300,
                   env={**os.environ, "OPENBLAS_CORETYPE": "Nehalem"})
    rec = json.loads((run / "physics.json").read_text())
    assert rec["blas"].endswith(" Nehalem") and rec["numpy_simd"] and rec["robot"] == "nao"
    s = get_study("humanoid-walk")
    cfg = resolve_config(s, None, [*TINY, "run.generations=2"])
    run_study(s, cfg, run, quiet=True, resume=True)
    log = (run / "log.txt").read_text()
    assert "resumed on other physics" in log and "Nehalem" in log
    assert json.loads((run / "physics.json").read_text())["blas"] == here
    # written before the host was recorded: no note
    old = {k: v for k, v in rec.items() if k not in ("numpy", "numpy_simd", "blas")}
    (run / "physics.json").write_text(json.dumps(old))
    run_study(s, resolve_config(s, None, [*TINY, "run.generations=3"]), run, quiet=True,
              resume=True)
    assert (run / "log.txt").read_text().count("resumed on other physics") == 1
