"""humanoid-balance: the task's physics (stand-still, pushes), the run's files, compare and
replay of a run folder, one-line errors."""

from __future__ import annotations

import json
import subprocess
import sys

import numpy as np
import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.sim.worlds import simulate_worlds
from evomotion.studies import get_study
from evomotion.studies.humanoid_balance.compare import compare, compare_command, table
from evomotion.studies.humanoid_balance.problem import (
    HumanoidBalanceConfig,
    HumanoidBalanceProblem,
)
from evomotion.studies.policy_search import policy_rows

TINY = ("problem.duration_s=0.4", "problem.eval_episodes=1", "problem.episodes=1",
        "problem.validate_episodes=2", "problem.threads=1", "algorithm.pop_size=4",
        "algorithm.top_directions=0", "run.generations=1", "run.videos=false", "run.seed=5")


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    out = tmp_path_factory.mktemp("balance") / "run"
    s = get_study("humanoid-balance")
    run_study(s, resolve_config(s, None, list(TINY)), out, quiet=True)
    return out


def _problem(**kw) -> HumanoidBalanceProblem:
    base = {"duration_s": 1.0, "threads": 1, "push_min_ns": 3.0, "push_max_ns": 3.0}
    return HumanoidBalanceProblem(HumanoidBalanceConfig(**{**base, **kw}))


def test_zero_policy_is_the_open_loop_stand_still():
    """The zero policy (what compare calls stand-still) is the nominal pose played open loop
    in the same pushed, perturbed worlds: same torso track, same falls."""
    p = _problem()
    seeds = np.arange(4) + 11
    o = p.obs_dim
    ep = p.play(np.zeros((4, p.genome.dim)), np.zeros((4, o)), np.ones((4, o)), seeds,
                record_states=True)
    worlds = p.worlds(seeds)
    ctrl = np.broadcast_to(p.sim.nominal, (p.nstep, p.robot.model.nu))
    states = simulate_worlds(worlds, p.robot.state0, ctrl, 1, segment_steps=p.control_steps,
                             stopped=lambda seg: np.zeros(len(seg), bool))
    k = p.control_steps
    open_loop = states[:, k - 1::k]  # after each control step
    steps = np.ceil(ep.result.steps / k).astype(int)
    for i in range(4):
        np.testing.assert_array_equal(ep.result.states[i, 1:steps[i] + 1],
                                      open_loop[i, :steps[i]])


def test_a_push_moves_the_torso_and_its_size_matters():
    p = _problem(perturb=False, duration_s=0.6, push_window_start=0.1, push_window_end=0.1)
    o, seeds = p.obs_dim, np.array([7, 7])
    zero = (np.zeros((1, p.genome.dim)), np.zeros((1, o)), np.ones((1, o)))
    still = p.play(*zero, seeds[:1], push_ns=0.0)
    pushed = p.play(*zero, seeds[:1], push_ns=3.0)
    w = p.worlds(seeds[:1], 3.0)[0]
    assert np.hypot(*w.push_ns[:2]) == pytest.approx(3.0) and w.push_ns[2] == 0.0
    v_still = np.abs(still.result.torso[0, :, 7:9]).max()
    v_pushed = np.abs(pushed.result.torso[0, :, 7:9]).max()
    assert v_still < 0.05 and v_pushed > 0.3  # 3 N s on 5.3 kg: ~0.57 m/s
    direction = pushed.result.torso[0, 8, 7:9]  # velocity just after the push at 0.06 s
    cos = direction @ np.asarray(w.push_ns[:2]) / np.linalg.norm(direction) / 3.0
    assert cos > 0.9


def test_push_directions_cover_the_circle_and_magnitudes_the_range():
    p = _problem(push_min_ns=1.0, push_max_ns=4.0)
    pushes = np.array([w.push_ns for w in p.worlds(np.arange(200))])
    mag = np.hypot(pushes[:, 0], pushes[:, 1])
    assert mag.min() >= 1.0 and mag.max() <= 4.0 and np.all(pushes[:, 2] == 0)
    angles = np.arctan2(pushes[:, 1], pushes[:, 0])
    assert np.histogram(angles, bins=4, range=(-np.pi, np.pi))[0].min() > 30


def test_evaluation_rows_are_independent_of_their_neighbours():
    p = _problem(duration_s=0.3)
    rng = np.random.default_rng(0)
    g = 0.05 * rng.standard_normal((3, p.genome.dim))
    rows = policy_rows(g, np.zeros(p.obs_dim), np.ones(p.obs_dim), 3, 2)
    ev = p.evaluate(rows)
    np.testing.assert_array_equal(p.evaluate(rows[1:2]).fitness, ev.fitness[1:2])
    assert set(ev.metrics) >= set(p.metric_names)
    assert np.all((ev.metrics["survived"] >= 0) & (ev.metrics["survived"] <= 1))


def test_run_writes_the_policy_and_its_description(run_dir):
    for name in ("policy.npz", "policy.py", "policy.json", "best.json", "stats.csv"):
        assert (run_dir / name).is_file(), name
    info = json.loads((run_dir / "policy.json").read_text())
    p = _problem()
    assert info["robot"] == "nao" and info["observations"] == list(p.obs_names)
    assert len(info["joints"]) == len(info["nominal_rad"]) == p.act_dim
    assert info["control_period_s"] == 0.02 and info["control_steps"] == 5
    log = (run_dir / "log.txt").read_text()
    assert "humanoid-balance: best validated centre score" in log  # the default validates
    assert "evomotion humanoid-balance compare RUN measures it" in log


def test_run_writes_the_naoqi_runner_beside_the_policy(run_dir):
    """``naoqi/``: the runner and its policy.json, whose policy is ``policy.py``'s."""
    import importlib.util

    folder = run_dir / "naoqi"
    record = json.loads((folder / "policy.json").read_text())
    info = json.loads((run_dir / "policy.json").read_text())
    assert [c["name"] for c in record["observation"]] == info["observations"]
    assert record["joints"] == info["joints"] and record["control_period_s"] == 0.02
    assert "joint_vel" in record["approximated"]  # the NAO has no joint velocity sensor
    mods = []
    for name, path in (("run_policy", run_dir / "policy.py"),
                       ("run_runner", folder / "policy_runner.py")):
        spec = importlib.util.spec_from_file_location(name, path)
        mods.append(importlib.util.module_from_spec(spec))
        spec.loader.exec_module(mods[-1])
    standalone = mods[0].load(run_dir / "policy.npz")
    runner = mods[1].Policy(record)
    obs = np.random.default_rng(0).normal(0.0, 1.0, (10, len(record["obs_mean"])))
    np.testing.assert_allclose([runner(list(x)) for x in obs], standalone(obs), rtol=0,
                               atol=1e-12)


def test_compare_prints_a_table_and_json(run_dir):
    text = compare_command(run_dir, worlds=3, push_ns=4.0)
    assert "| evolved policy |" in text and "| stand still (open loop) |" in text
    assert "4 N s" in text
    res = compare(run_dir, worlds=3, push_ns=4.0)
    assert set(res["policy"]) == {"survival", "time_up_s", "tilt_rad", "score"}
    assert 0 <= res["stand_still"]["survival"] <= 1 and table(res) == text


def test_compare_refuses_bad_input_in_one_line(run_dir, tmp_path):
    with pytest.raises(InputError, match="--worlds"):
        compare(run_dir, worlds=0)
    with pytest.raises(InputError, match="--push"):
        compare(run_dir, worlds=2, push_ns=float("nan"))
    with pytest.raises(InputError, match="expected a humanoid-balance run folder"):
        compare(tmp_path / "nothing")


def _cli(*args: str):
    return subprocess.run([sys.executable, "-m", "evomotion.cli", *args], capture_output=True,
                          text=True, timeout=120)


def test_replay_of_a_run_folder_and_of_a_bad_one(run_dir, tmp_path):
    r = _cli("replay", str(run_dir), "--stress", "2")
    assert r.returncode == 0, r.stderr
    assert "policy of run" in r.stdout and "2 perturbed worlds" in r.stdout
    r = _cli("replay", str(run_dir / "policy.npz"), "--json")
    assert r.returncode == 0 and json.loads(r.stdout)["robot"] == "nao"
    bad = tmp_path / "not-a-run"
    bad.mkdir()
    r = _cli("replay", str(bad))
    assert r.returncode != 0 and "Traceback" not in r.stderr
    assert len(r.stderr.strip().splitlines()) == 1 and "not a run folder" in r.stderr


def test_bad_config_is_one_line():
    with pytest.raises(InputError, match="control_period_s"):
        HumanoidBalanceProblem(HumanoidBalanceConfig(control_period_s=0.01))
    with pytest.raises(InputError, match="observation channel"):
        HumanoidBalanceProblem(HumanoidBalanceConfig(observations="joint_pos,nose"))
    with pytest.raises(InputError, match="push_max_ns"):
        HumanoidBalanceConfig(push_min_ns=3.0, push_max_ns=2.0).validate()
    with pytest.raises(InputError, match="problem.stance_width_rad"):
        HumanoidBalanceConfig(stance_width_rad=2.0).validate()
    with pytest.raises(InputError, match="problem.stance_width_rad.*AnkleRoll at"):
        HumanoidBalanceProblem(HumanoidBalanceConfig(stance_width_rad=0.6, threads=1))


def test_the_default_validates_and_a_folder_from_before_it_resumes_as_it_ran(tmp_path):
    """The default exports the best centre on fixed validation episodes; a run folder written
    before ``problem.validate_every`` existed (it exported the best single centre score) is
    read with validation off and resumed bit for bit as the run it was."""
    from evomotion.run.config import config_from_run_dir
    from evomotion.run.stats import read_stats

    study = get_study("humanoid-balance")
    default = resolve_config(study, None, []).problem
    assert (default.validate_every, default.validate_episodes, default.eval_episodes) == (
        10, 128, 8)
    tiny = [t for t in TINY if not t.startswith("run.generations")]
    old = [*tiny, "problem.validate_every=0", "problem.validate_episodes=32",
           "run.checkpoint_every=1"]
    full, part = tmp_path / "full", tmp_path / "part"
    for out, gens in ((full, 3), (part, 2)):
        run_study(study, resolve_config(study, None, [*old, f"run.generations={gens}"]), out,
                  quiet=True)
    _without_keys(part, "validate_")  # as written before the keys existed
    assert "validate_" not in (part / "config.toml").read_text()
    assert config_from_run_dir(part)[1]["problem"]["validate_every"] == 0
    proc = subprocess.run([sys.executable, "-m", "evomotion.cli", "resume", str(part), "--set",
                           "run.generations=3", "--quiet"], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    a, b = read_stats(full / "stats.csv"), read_stats(part / "stats.csv")
    assert "valid_return" not in b and len(b["generation"]) == 4
    for col in set(a) - {"wall_s", "evals_per_s"}:
        np.testing.assert_array_equal(a[col], b[col], err_msg=col)
    assert (full / "policy.npz").read_bytes() == (part / "policy.npz").read_bytes()


SPEC_POSE = ("problem.stance_width_rad=0", "problem.stance_stagger_rad=0",
             "problem.stance_crouch_rad=0")


def _without_keys(run, prefix: str) -> None:
    """Make ``run`` look written before the problem keys ``prefix*`` existed: none in its
    ``config.toml`` nor in its checkpoints' config records."""
    import re

    cfg = run / "config.toml"
    cfg.write_text(re.sub(rf"^{prefix}\w+ = .*\n", "", cfg.read_text(), flags=re.M))
    for ck in (run / "checkpoints").glob("gen-*.json"):
        meta = json.loads(ck.read_text())
        meta["config"] = {k: v for k, v in meta["config"].items() if prefix not in k}
        ck.write_text(json.dumps(meta))


def _before_the_stance(run) -> None:
    """Make ``run`` look written before problem.stance_* existed: no such keys anywhere, and no
    ``physics.json`` (recorded since 2026-12-05)."""
    (run / "physics.json").unlink()
    _without_keys(run, "stance_")


def test_the_default_stance_is_wider_and_a_folder_from_before_it_resumes_in_the_spec_pose(
        tmp_path):
    """The default stands in the wide, staggered, lower stance (sim/stance.py); a run folder
    written before the stance keys existed (it stood in the spec pose) is read, and resumed
    bit for bit, as the run it was."""
    from evomotion.run.config import config_from_run_dir
    from evomotion.sim.robots import load_robot
    from evomotion.studies.humanoid_balance.compare import load_run

    spec = load_robot("nao").pose
    assert not np.array_equal(HumanoidBalanceProblem(HumanoidBalanceConfig(threads=1))
                              .robot.pose, spec)
    tiny = [*(t for t in TINY if not t.startswith("run.generations")), *SPEC_POSE]
    full, part = tmp_path / "full", tmp_path / "part"
    for out, gens in ((full, 3), (part, 2)):
        sets = [a for t in (*tiny, f"run.generations={gens}") for a in ("--set", t)]
        proc = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "humanoid-balance",
                               *sets, "--out", str(out), "--quiet"], capture_output=True,
                              text=True, timeout=600)
        assert proc.returncode == 0, proc.stderr
    _before_the_stance(part)
    assert "stance_" not in (part / "config.toml").read_text()
    raw = config_from_run_dir(part)[1]["problem"]
    assert [raw[k] for k in ("stance_width_rad", "stance_stagger_rad",
                             "stance_crouch_rad", "stance_lean_rad")] == [0.0, 0.0, 0.0, 0.0]
    problem = load_run(part)[0]
    np.testing.assert_array_equal(problem.robot.pose, spec)
    problem.sim.close()
    # its config.toml fed back as --config reruns it in the spec pose, and the API reads it so;
    # a hand-written file without the keys takes the defaults
    import evomotion as em
    from evomotion.run.config import resolve_config
    from evomotion.studies import get_study

    study, zeros = get_study("humanoid-balance"), (0.0, 0.0, 0.0)

    def stance(cfg):
        return (cfg.stance_width_rad, cfg.stance_stagger_rad, cfg.stance_crouch_rad)

    assert stance(resolve_config(study, part / "config.toml").problem) == zeros
    assert tuple(em.load_run(part).config["problem"][k] for k in (
        "stance_width_rad", "stance_stagger_rad", "stance_crouch_rad")) == zeros
    hand = tmp_path / "hand.toml"
    hand.write_text('study = "humanoid-balance"\n[problem]\nduration_s = 2.0\n')
    assert stance(resolve_config(study, hand).problem) == stance(HumanoidBalanceConfig())
    proc = subprocess.run([sys.executable, "-m", "evomotion.cli", "resume", str(part), "--set",
                           "run.generations=3", "--quiet"], capture_output=True, text=True,
                          timeout=600)
    assert proc.returncode == 0, proc.stderr
    from evomotion.run.stats import read_stats

    a, b = read_stats(full / "stats.csv"), read_stats(part / "stats.csv")
    assert len(a["generation"]) == len(b["generation"]) == 4
    for col in set(a) - {"wall_s", "evals_per_s"}:
        np.testing.assert_array_equal(a[col], b[col], err_msg=col)
    # the resume wrote the record the old folder lacked, without a note about other physics
    assert json.loads((part / "physics.json").read_text())["backend"] == "cpu"
    assert "other physics" not in (part / "log.txt").read_text()


def test_a_folder_from_before_the_lean_reads_as_standing_upright_in_its_own_stance():
    """A run config with the stance's first three keys but no ``stance_lean_rad`` (written
    before the lean existed) reads as the run it was: its own stance, no lean."""
    from evomotion.run.config import as_now

    raw = {"study": "humanoid-balance", "problem": {
        "stance_width_rad": 0.3, "stance_stagger_rad": 0.2, "stance_crouch_rad": 0.15}}
    problem = as_now(raw)["problem"]
    assert problem == {"stance_width_rad": 0.3, "stance_stagger_rad": 0.2,
                       "stance_crouch_rad": 0.15, "stance_lean_rad": 0.0,
                       "validate_every": 0, "validate_episodes": 32}
