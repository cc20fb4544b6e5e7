"""Every optimizer a policy search runs (ARS, OpenAI-ES, PGPE, SNES, CMA-ES) through the gym
study: an interrupted run resumes bit-identically, and the process evaluator gives the serial
evaluator's results (the normaliser and the episode seeds travel in the rows)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("gymnasium")

from evomotion.run.config import resolve_config  # noqa: E402
from evomotion.run.faults import fault_at  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402
from evomotion.run.stats import read_stats  # noqa: E402
from evomotion.studies.gym.study import POLICY_OPTIMIZERS, STUDY  # noqa: E402

SETTINGS = ["problem.max_episode_steps=25", "problem.eval_episodes=2", "run.generations=4",
            "run.checkpoint_every=2", "run.seed=5", "algorithm.pop_size=6", "run.evaluator=serial"]
TIMED = {"wall_s", "evals_per_s"}


def _same(a: Path, b: Path) -> None:
    s1, s2 = read_stats(a / "stats.csv"), read_stats(b / "stats.csv")
    assert list(s1) == list(s2)
    for col in s1:
        if col not in TIMED:
            np.testing.assert_array_equal(s1[col], s2[col], err_msg=col)
    assert json.loads((a / "best.json").read_text())["genome"] == \
        json.loads((b / "best.json").read_text())["genome"]
    assert (a / "policy.npz").read_bytes() == (b / "policy.npz").read_bytes()


CASES = [(name, ()) for name in POLICY_OPTIMIZERS] + [("ars", ("algorithm.noise_table=5000",)),
                                                       ("snes", ("algorithm.noise_table=5000",))]


@pytest.mark.parametrize("name, more", CASES)
def test_resume_and_process_evaluator_are_bit_identical(name, more, tmp_path):
    extra = [*(["algorithm.top_directions=0"] if name == "ars" else []), *more]
    cfg = resolve_config(STUDY, None, [*SETTINGS, f"algorithm.name={name}", *extra])
    run_study(STUDY, cfg, tmp_path / "full", quiet=True)
    with fault_at(3, "interrupt"):
        run_study(STUDY, cfg, tmp_path / "cut", quiet=True)
    run_study(STUDY, cfg, tmp_path / "cut", quiet=True, resume=True)
    _same(tmp_path / "full", tmp_path / "cut")
    proc = resolve_config(STUDY, None, [*SETTINGS, f"algorithm.name={name}", *extra,
                                        "run.evaluator=process", "run.workers=2"])
    run_study(STUDY, proc, tmp_path / "proc", quiet=True)
    _same(tmp_path / "full", tmp_path / "proc")
