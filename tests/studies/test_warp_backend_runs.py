"""The step, walk, repertoire and balance studies on the MuJoCo Warp backend (Warp's CPU
device): the GA / CMA-ES / MAP-Elites / ARS loop runs end to end through the one run loop, the
run folder records the backend, and an interrupted run resumes bit-identically (Warp's CPU
device runs every kernel in a fixed order, with ``warp_deterministic`` off, the default, as
on)."""

from __future__ import annotations

import json

import numpy as np
import pytest

pytest.importorskip("mujoco_warp")

from evomotion.errors import InputError  # noqa: E402
from evomotion.run.config import resolve_config  # noqa: E402
from evomotion.run.faults import fault_at  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402
from evomotion.run.stats import read_stats  # noqa: E402
from evomotion.studies import get_study  # noqa: E402

WARP = ("problem.backend=warp", "problem.warp_device=cpu")
TIMED = {"wall_s", "evals_per_s"}


def _overrides(name: str) -> list[str]:
    return [*get_study(name).smoke, *WARP, "run.generations=1", "run.checkpoint_every=1",
            "run.wall_seconds=0", "run.seed=5", "run.videos=false"]


@pytest.mark.parametrize("name", ["humanoid-step", "humanoid-walk-open-loop",
                                  "humanoid-repertoire", "humanoid-balance"])
def test_study_runs_on_warp_and_resumes_bit_identically(name, tmp_path):
    s = get_study(name)
    cfg = resolve_config(s, None, _overrides(name))
    full = run_study(s, cfg, tmp_path / "full", quiet=True)
    assert full.generation == 1
    physics = json.loads((tmp_path / "full" / "physics.json").read_text())
    assert physics["backend"] == "warp" and physics["device"] == "cpu"
    assert physics["precision"] == "float32" and physics["deterministic"] is False
    assert "physics: backend warp on cpu" in (tmp_path / "full" / "log.txt").read_text()
    best = json.loads((tmp_path / "full" / "best.json").read_text())
    assert np.isfinite(best["fitness"])

    with fault_at(1, "interrupt"):  # during generation 1, after the checkpoint of 0
        cut = run_study(s, cfg, tmp_path / "cut", quiet=True)
    assert cut.stop_reason == "interrupted"
    run_study(s, cfg, tmp_path / "cut", quiet=True, resume=True)
    a, b = read_stats(tmp_path / "full" / "stats.csv"), read_stats(tmp_path / "cut" / "stats.csv")
    for col in a:
        if col not in TIMED:
            np.testing.assert_array_equal(a[col], b[col], err_msg=col)
    assert best == json.loads((tmp_path / "cut" / "best.json").read_text())


@pytest.mark.parametrize("name", ["humanoid-step", "humanoid-balance"])
def test_cpu_run_records_its_physics(name, tmp_path):
    s = get_study(name)
    over = [*s.smoke, "run.generations=0"]
    run_study(s, resolve_config(s, None, over), tmp_path / "r", quiet=True)
    physics = json.loads((tmp_path / "r" / "physics.json").read_text())
    assert physics["backend"] == "cpu" and physics["precision"] == "float64"
    assert "physics:" not in (tmp_path / "r" / "log.txt").read_text()
    if name == "humanoid-balance":  # the robot in its stance is still the NAO's spec and MJCF
        assert physics["robot"] == "nao"
        assert "?" not in (physics["robot_spec_sha256"], physics["robot_mjcf_sha256"])


def test_resume_on_other_physics_is_noted(tmp_path):
    s = get_study("humanoid-step")
    over = [*s.smoke, "run.generations=1", "run.checkpoint_every=1", "run.wall_seconds=0"]
    cfg = resolve_config(s, None, over)
    with fault_at(1, "interrupt"):
        run_study(s, cfg, tmp_path / "r", quiet=True)
    rec = tmp_path / "r" / "physics.json"
    rec.write_text(json.dumps(dict(json.loads(rec.read_text()), mujoco="0.0.1")))
    run_study(s, cfg, tmp_path / "r", quiet=True, resume=True)
    assert "resumed on other physics" in (tmp_path / "r" / "log.txt").read_text()


def test_bad_backend_settings_are_one_line():
    s = get_study("humanoid-step")
    with pytest.raises(InputError, match="problem.backend"):
        resolve_config(s, None, ["problem.backend=gpu"])
    with pytest.raises(InputError, match="problem.warp_nconmax"):
        resolve_config(s, None, ["problem.warp_nconmax=0"])


def test_a_population_too_large_for_the_device_is_refused(monkeypatch):
    from evomotion.sim import warp_memory

    s = get_study("humanoid-step")
    cfg = resolve_config(s, None, [*s.smoke, *WARP, "algorithm.pop_size=4096"])
    monkeypatch.setattr(warp_memory, "free_bytes", lambda device: 10**8)
    with pytest.raises(InputError, match=r"algorithm.pop_size=4096, problem.backend=warp: one "
                                         r"batch needs about .* on cpu, more than the 100.0 MB"):
        run_study(s, cfg, None, quiet=True)
