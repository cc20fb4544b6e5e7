"""The gym study end to end: a run through the run loop, its exported policy in a plain
Gymnasium loop, and one-line errors."""

from __future__ import annotations

import importlib.util
import subprocess
import sys

import numpy as np
import pytest

gym = pytest.importorskip("gymnasium")

from evomotion.core.policies.export import read_policy_npz  # noqa: E402
from evomotion.studies.gym.problem import GymConfig, GymProblem  # noqa: E402
from evomotion.studies.policy_search import policy_rows  # noqa: E402


def _run(tmp_path, *sets: str):
    out = tmp_path / "run"
    cmd = [sys.executable, "-m", "evomotion.cli", "run", "gym", "--out", str(out),
           "--set", "problem.max_episode_steps=60", "--set", "problem.eval_episodes=2",
           "--set", "run.generations=4", *[a for s in sets for a in ("--set", s)]]
    r = subprocess.run(cmd, capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    return out


def _load(path):
    spec = importlib.util.spec_from_file_location("exported_policy", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def test_exported_policy_scores_in_a_plain_gymnasium_loop_as_in_the_run(tmp_path):
    """policy.py (numpy only) in Gymnasium's own loop on a seed gives the return the study's
    evaluation gives that policy on the same seed; ONNX agrees with it to 1e-5."""
    out = _run(tmp_path)
    for name in ("policy.npz", "policy.py", "policy.onnx", "stats.csv", "best.json"):
        assert (out / name).is_file(), name
    exported = read_policy_npz(out / "policy.npz")
    policy = _load(out / "policy.py").load(str(out / "policy.npz"))
    env = gym.make("Hopper-v5", max_episode_steps=60)
    obs, _ = env.reset(seed=123)
    ret, seen = 0.0, []
    for _ in range(60):
        seen.append(obs)
        obs, r, term, trunc, _ = env.step(policy(obs))
        ret += r
        if term or trunc:
            break
    problem = GymProblem(GymConfig(max_episode_steps=60))
    row = policy_rows(exported.params[None], exported.obs_mean, exported.obs_std, 123, 1)
    assert problem.evaluate(row).metrics["return"][0] == pytest.approx(ret, abs=1e-9)
    ort = pytest.importorskip("onnxruntime")
    sess = ort.InferenceSession(str(out / "policy.onnx"))
    x = np.asarray(seen, dtype=np.float32)
    got = sess.run(None, {"observation": x})[0]
    np.testing.assert_allclose(got, np.stack([policy(o) for o in seen]), atol=1e-5)


def test_the_centre_is_what_the_run_reports(tmp_path):
    out = _run(tmp_path, "algorithm.name=openai_es", "algorithm.pop_size=8")
    import csv

    with open(out / "stats.csv") as f:
        rows = list(csv.DictReader(f))
    best = max(float(r["centre_return"]) for r in rows)
    assert float(rows[-1]["best_so_far"]) == pytest.approx(best)
    assert int(rows[-1]["train_episodes"]) == len(rows) * 8  # 8 individuals, 1 episode each


def test_bad_env_is_one_line(tmp_path):
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "gym", "--out",
                        str(tmp_path / "x"), "--set", "problem.env=NoSuchEnv-v0"],
                       capture_output=True, text=True, timeout=120)
    assert r.returncode != 0 and "Traceback" not in r.stderr
    assert "problem.env" in r.stderr and len(r.stderr.strip().splitlines()) == 1


def test_batched_backend_refuses_what_it_cannot_step():
    from evomotion.errors import InputError

    with pytest.raises(InputError, match="problem.backend"):
        GymProblem(GymConfig(env="Pendulum-v1", backend="batched"))
    p = GymProblem(GymConfig(env="Pendulum-v1"))
    assert p.backend == "gymnasium"
    ev = p.evaluate(p.evaluation_rows(np.zeros((2, p.genome.dim))))
    assert ev.fitness.shape == (2,) and np.all(ev.metrics["steps"] == 200)


def test_nothing_is_written_beside_the_run_folder(tmp_path):
    """Swimmer's model makes MuJoCo warn, which by default writes MUJOCO_LOG.TXT into the
    working folder; the study keeps it out."""
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "gym", "--out", "run",
                        "--set", "problem.env=Swimmer-v5", "--set", "run.generations=1",
                        "--set", "problem.max_episode_steps=5"], cwd=tmp_path,
                       capture_output=True, text=True, timeout=120)
    assert r.returncode == 0, r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["run"]
    assert "WARNING" not in r.stderr


def test_replay_plays_the_exported_policy_on_unseen_episodes(tmp_path):
    import json

    out = _run(tmp_path)
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "replay", str(out), "--stress",
                        "3", "--json"], capture_output=True, text=True, timeout=300)
    assert r.returncode == 0, r.stderr
    summary = json.loads(r.stdout)
    assert summary["episodes"] == 3 and summary["env"] == "Hopper-v5"
    assert summary["return_min"] <= summary["return_mean"] <= summary["return_max"]
    r = subprocess.run([sys.executable, "-m", "evomotion.cli", "replay", str(out), "--push",
                        "1"], capture_output=True, text=True, timeout=300)
    assert r.returncode != 0 and "Traceback" not in r.stderr and "--push" in r.stderr


def test_physics_json_records_gymnasium_and_a_resume_on_another_is_noted(tmp_path):
    """The run records what its bits depend on (MuJoCo, Gymnasium, how the environment is
    stepped, the host's numpy and BLAS); resumed where the record differs, the log says the
    result is not bit-identical; a folder written before gym recorded physics resumes
    without a note."""
    import json

    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies.gym.study import STUDY

    sets = ["problem.max_episode_steps=20", "problem.eval_episodes=1", "algorithm.pop_size=4",
            "run.evaluator=serial", "run.checkpoint_every=1"]
    run = tmp_path / "r"
    run_study(STUDY, resolve_config(STUDY, None, [*sets, "run.generations=1"]), run, quiet=True)
    rec = json.loads((run / "physics.json").read_text())
    assert rec["gymnasium"] == gym.__version__ and rec["env"] == "Hopper-v5"
    assert rec["env_backend"] == "batched" and rec["backend"] == "cpu" and rec["blas"]
    (run / "physics.json").write_text(json.dumps({**rec, "gymnasium": "0.0.1"}))
    run_study(STUDY, resolve_config(STUDY, None, [*sets, "run.generations=2"]), run, quiet=True,
              resume=True)
    log = (run / "log.txt").read_text()
    assert "resumed on other physics" in log and "0.0.1" in log
    assert json.loads((run / "physics.json").read_text())["gymnasium"] == gym.__version__
    (run / "physics.json").unlink()  # written before 2026-12-07
    run_study(STUDY, resolve_config(STUDY, None, [*sets, "run.generations=3"]), run, quiet=True,
              resume=True)
    assert (run / "log.txt").read_text().count("resumed on other physics") == 1
