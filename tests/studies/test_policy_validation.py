"""The exported policy chosen on fixed validation episodes (``problem.validate_every``,
studies/policy_validation.py): the search is the same with it on or off, the export is the
validated centre with the score it had, a resume is bit-identical, every evaluator agrees, and
bad values are one line."""

from __future__ import annotations

import csv
import json

import numpy as np
import pytest

from evomotion.core.policies.export import read_policy_npz
from evomotion.errors import InputError
from evomotion.studies.policy_search import make_policy_driver, policy_rows
from evomotion.studies.policy_validation import (
    VALID_SEED_BASE,
    due,
    validation_cost,
    validation_seeds,
)

gym = pytest.importorskip("gymnasium")

from evomotion.run.config import resolve_config  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402
from evomotion.studies.gym.problem import GymConfig, GymProblem  # noqa: E402
from evomotion.studies.gym.study import STUDY as GYM  # noqa: E402

SETS = ("problem.max_episode_steps=40", "problem.eval_episodes=2", "run.evaluator=serial",
        "algorithm.name=ars", "algorithm.pop_size=4", "algorithm.top_directions=0")
VALIDATE = ("problem.validate_every=3", "problem.validate_episodes=5")


def _cfg(*sets: str):
    return resolve_config(GYM, None, [*SETS, *sets])


def _stats(run) -> list[dict[str, str]]:
    with open(run / "stats.csv", newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    base = tmp_path_factory.mktemp("val")
    off, on = base / "off", base / "on"
    run_study(GYM, _cfg("run.generations=8"), off, quiet=True)
    run_study(GYM, _cfg("run.generations=8", *VALIDATE), on, quiet=True)
    return off, on


def test_the_search_is_the_same_with_validation_on_or_off(runs):
    off, on = (_stats(r) for r in runs)
    assert len(off) == len(on) == 9  # generations 0 to 8
    for a, b in zip(off, on, strict=True):
        for key in ("best", "mean", "min", "max", "centre_return", "train_episodes"):
            assert a[key] == b[key], key
    assert "valid_return" not in off[0]
    # validated at generations 0, 3 and 6 only, each time on 5 more episodes
    assert [r["valid_return"] != "nan" for r in on] == [due(g, 3) for g in range(9)]
    assert [int(b["evaluations"]) - int(a["evaluations"]) for a, b in zip(off, on, strict=True)
            ] == [5, 5, 5, 10, 10, 10, 15, 15, 15]


def test_the_export_is_the_best_validated_centre_with_the_score_it_had(runs):
    _, on = runs
    rec = json.loads((on / "best.json").read_text())
    rows = _stats(on)
    scores = [float(r["valid_return"]) for r in rows if r["valid_return"] != "nan"]
    assert rec["validated"]["return"] == max(scores) == rec["fitness"]
    assert rec["validated"]["generation"] in (0, 3, 6)
    assert float(rows[-1]["best_so_far"]) == max(scores)
    # the exported file plays the validation episodes to the same mean return
    cfg = _cfg(*VALIDATE)
    problem = GymProblem(cfg.problem)
    got = read_policy_npz(on / "policy.npz")
    seeds = validation_seeds(5)
    again = problem.evaluate(policy_rows(np.repeat(got.params[None], 5, axis=0), got.obs_mean,
                                         got.obs_std, seeds, 1)).metrics["return"]
    assert -validation_cost(again) == rec["validated"]["return"]


def test_a_validated_run_resumes_bit_for_bit(runs, tmp_path):
    _, whole = runs
    split = tmp_path / "split"
    run_study(GYM, _cfg("run.generations=4", *VALIDATE), split, quiet=True)
    run_study(GYM, _cfg("run.generations=8", *VALIDATE), split, quiet=True, resume=True)
    assert (whole / "policy.npz").read_bytes() == (split / "policy.npz").read_bytes()
    clock = ("wall_s", "evals_per_s")
    assert [{k: v for k, v in r.items() if k not in clock} for r in _stats(whole)] == \
        [{k: v for k, v in r.items() if k not in clock} for r in _stats(split)]


def test_the_process_evaluator_exports_the_same_policy(runs, tmp_path):
    _, serial = runs
    out = tmp_path / "proc"
    run_study(GYM, _cfg("run.generations=8", *VALIDATE, "run.evaluator=process",
                        "run.workers=2"), out, quiet=True)
    assert (serial / "policy.npz").read_bytes() == (out / "policy.npz").read_bytes()


def test_a_checkpoint_from_before_validation_restores_and_validates():
    cfg = _cfg(*VALIDATE)
    driver = make_policy_driver(GymProblem(cfg.problem), cfg)
    state = driver.init(np.random.default_rng(0))
    arrays, meta = driver.state_arrays(state)
    old_arrays = {k: v for k, v in arrays.items() if not k.startswith("valid.")}
    old_meta = {k: v for k, v in meta.items() if k != "generation" and
                not k.startswith("valid")}
    back = driver.restore(old_arrays, old_meta)
    assert back.generation == 0 and back.valid is None
    driver.check_state(back)
    bad = dict(arrays, **{"valid.x": np.zeros(3)})
    with pytest.raises(ValueError, match="validated policy"):
        driver.check_state(driver.restore(bad, meta))


def test_seeds_and_costs():
    assert validation_seeds(3).tolist() == [VALID_SEED_BASE, VALID_SEED_BASE + 1,
                                            VALID_SEED_BASE + 2]
    assert float(VALID_SEED_BASE + 1023) == VALID_SEED_BASE + 1023  # exact in a row
    assert validation_cost(np.array([1.0, 3.0])) == -2.0
    assert validation_cost(np.array([1.0, np.nan])) == float("inf")
    assert validation_cost(np.array([])) == float("inf")
    assert not due(5, 0) and due(0, 7) and due(14, 7) and not due(15, 7)


@pytest.mark.parametrize("key, value", [("validate_every", -1), ("validate_every", 1.5),
                                        ("validate_every", True), ("validate_episodes", 0),
                                        ("validate_episodes", 5000),
                                        ("validate_episodes", "8")])
def test_bad_values_are_one_line_naming_the_key(key, value):
    with pytest.raises(InputError, match=f"problem.{key}: expected"):
        GymConfig(**{key: value}).validate()


def test_the_validated_export_does_not_depend_on_the_centre_episodes(runs, tmp_path):
    """The centre's own episodes draw their seeds whatever their number and train nothing, so
    with validation a run may score the centre on fewer of them and export the same file."""
    _, on = runs
    out = tmp_path / "fewer"
    run_study(GYM, _cfg("run.generations=8", *VALIDATE, "problem.eval_episodes=1"), out,
              quiet=True)
    assert (on / "policy.npz").read_bytes() == (out / "policy.npz").read_bytes()
