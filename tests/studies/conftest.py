"""Makes the studies' shared test helpers (``hostile_cli``) importable from every study's
test folder; ``omniwalk_run``: a tiny humanoid-walk run (one generation) whose exported
controller the kick's ``play`` and ``walk-to`` walk with."""

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).parent))

OMNIWALK_TINY = ("problem.duration_s=1.0", "problem.eval_episodes=1", "problem.episodes=1",
                 "problem.threads=1", "algorithm.pop_size=4", "algorithm.top_directions=0",
                 "run.generations=1", "run.videos=false")


@pytest.fixture(scope="session")
def omniwalk_run(tmp_path_factory):
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study
    from evomotion.studies import get_study

    out = tmp_path_factory.mktemp("omniwalk") / "run"
    s = get_study("humanoid-walk")
    assert run_study(s, resolve_config(s, None, list(OMNIWALK_TINY)), out,
                     quiet=True).exit_code == 0
    return out
