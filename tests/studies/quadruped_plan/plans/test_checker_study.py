"""plan.json round trip, the independent checker, the run driver and the CLI."""

from __future__ import annotations

import copy
import json
import math
from pathlib import Path

import pytest
from typer.testing import CliRunner

from evomotion.errors import FileFormatError
from evomotion.studies.quadruped_plan.plans.checker import PlanViolationError, check_plan
from evomotion.studies.quadruped_plan.plans.experiment import (
    PAPER_FIGURES,
    format_table,
    run_config,
)
from evomotion.studies.quadruped_plan.plans.plan import plan_document, read_plan, write_plan
from evomotion.studies.quadruped_plan.plans.planner import QuadrupedPlanConfig, make_problem, solve
from evomotion.studies.quadruped_plan.plans.search_config import SearchConfig
from evomotion.studies.quadruped_plan.study import STUDY, cli


def run_plan(problem_cfg: QuadrupedPlanConfig, out: Path, **alg) -> int:
    """One run of the study through the run loop with this ``[problem]`` (``alg``: the
    ``[algorithm]`` keys)."""
    from evomotion.run.config import Config, RunSection
    from evomotion.run.runner import run_study

    out.mkdir(parents=True, exist_ok=True)
    cfg = Config("quadruped-plan", RunSection(generations=10**6), SearchConfig(**alg),
                 problem_cfg)
    return run_study(STUDY, cfg, out, quiet=True).exit_code

SHORT = QuadrupedPlanConfig(start_phi=0.0, goal_x=0.0, goal_y=-7.0, rule_set="B",
                            gif_max_frames=12)  # with the default search: function (3)


@pytest.fixture(scope="module")
def doc() -> dict:
    p = make_problem(SHORT)
    res = solve(SHORT, None, p)
    assert res.found
    return plan_document(p.model, res.states, res.rules, p.goal, SHORT.goal_tolerance,
                         SHORT.sense, SHORT.rule_set, None, {"expansions": res.expansions})


def test_plan_keys_and_round_trip(doc: dict, tmp_path: Path) -> None:
    st = doc["states"][1]
    assert set(st) == {"body", "feet", "rule", "margin"}
    assert len(st["body"]) == 3 and len(st["feet"]) == 4 and all(len(f) == 2 for f in st["feet"])
    assert doc["states"][0]["rule"] == 0 and doc["model"]["a"] == 2.5
    write_plan(tmp_path / "plan.json", doc)
    back = read_plan(tmp_path / "plan.json")
    assert back == json.loads(json.dumps(doc))
    assert check_plan(back)["states"] == len(doc["states"])


def _tampered(doc: dict, edit) -> dict:
    bad = copy.deepcopy(doc)
    edit(bad)
    return bad


def _first_leg_move(doc: dict) -> int:
    return next(i for i, s in enumerate(doc["states"]) if s["rule"] >= 4)


def _first_translation(doc: dict) -> int:
    return next(i for i, s in enumerate(doc["states"]) if s["rule"] in (2, 3))


@pytest.mark.parametrize("edit, words", [
    (lambda d: d["states"][-1]["feet"][0].__setitem__(0, 50.0), "outside its workspace"),
    (lambda d: d["states"][-1]["body"].__setitem__(0, 40.0), "workspace"),
    (lambda d: d["states"][1].__setitem__("margin", 9.0), "margin"),
    (lambda d: d["states"][1].__setitem__("rule", 99), "no such rule"),
    (lambda d: d["states"].pop(), "from the goal"),
    (lambda d: d.__setitem__("model", dict(d["model"], min_margin=5.0)), "lifted with margin"),
])
def test_checker_catches_violations(doc: dict, edit, words: str) -> None:
    with pytest.raises(PlanViolationError, match=words):
        check_plan(_tampered(doc, edit))


def test_checker_catches_wrong_rule_and_skipped_state(doc: dict) -> None:
    i = _first_leg_move(doc)
    other = 4 + ((doc["states"][i]["rule"] - 4) % 4 + 1) % 4  # same kind, other leg
    with pytest.raises(PlanViolationError, match="moved|not where"):
        check_plan(_tampered(doc, lambda d: d["states"][i].__setitem__("rule", other)))
    j = _first_translation(doc)
    with pytest.raises(PlanViolationError):  # drop the translation: a jump between states
        check_plan(_tampered(doc, lambda d: d["states"].pop(j)))


def test_read_plan_rejects_bad_files(tmp_path: Path) -> None:
    with pytest.raises(FileFormatError, match="existing"):
        read_plan(tmp_path / "missing.json")
    (tmp_path / "x.json").write_text("{\n  nope")
    with pytest.raises(FileFormatError, match="x.json:2"):
        read_plan(tmp_path / "x.json")
    (tmp_path / "y.json").write_text(json.dumps({"model": {}, "goal": [0, 0],
                                                 "goal_tolerance": 1, "rule_set": "A",
                                                 "states": []}))
    with pytest.raises(FileFormatError, match="model key"):
        read_plan(tmp_path / "y.json")


def test_run_plan_writes_run_folder(tmp_path: Path) -> None:
    assert run_plan(SHORT, tmp_path) == 0
    for name in ("plan.json", "plan.png", "plan.gif", "log.txt"):
        assert (tmp_path / name).stat().st_size > 0
    assert check_plan(read_plan(tmp_path / "plan.json"))["leg_moves"] > 0
    assert "checker: ok" in (tmp_path / "log.txt").read_text()


def test_unreachable_goal_and_zero_budget_exit_non_zero(tmp_path: Path) -> None:
    zone = QuadrupedPlanConfig(zone_x=-10, zone_y=10, zone_radius=2.0)
    assert run_plan(zone, tmp_path / "zone") == 1
    assert "inside the exclusion zone" in (tmp_path / "zone" / "log.txt").read_text()
    assert not (tmp_path / "zone" / "plan.json").exists()
    assert run_plan(QuadrupedPlanConfig(), tmp_path / "zero", max_expansions=0) == 1
    assert "expansion budget is spent (0 expansions" in (tmp_path / "zero" / "log.txt"
                                                           ).read_text()


def test_study_descriptor_and_runner_entry(tmp_path: Path) -> None:
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study

    assert STUDY.name == "quadruped-plan" and "search" in STUDY.algorithms
    cfg = resolve_config(STUDY, overrides=["problem.goal_y=-7.0", "problem.goal_x=0.0",
                                           "problem.start_phi=0.0", "problem.gif_max_frames=8"])
    assert run_study(STUDY, cfg, tmp_path, quiet=True).exit_code == 0
    assert (tmp_path / "config.toml").exists() and (tmp_path / "plan.gif").exists()


def test_batches_of_expansions_give_the_one_shot_plan(tmp_path: Path) -> None:
    assert run_plan(SHORT, tmp_path / "small", batch_expansions=97) == 0
    one = solve(SHORT, None, make_problem(SHORT))
    doc = read_plan(tmp_path / "small" / "plan.json")
    assert len(doc["states"]) == len(one.states)
    assert doc["search"]["expansions"] == one.expansions
    rows = (tmp_path / "small" / "stats.csv").read_text().splitlines()
    assert len(rows) - 1 == -(-one.expansions // 97)


def test_a_process_evaluator_is_refused(tmp_path: Path) -> None:
    from evomotion.errors import InputError
    from evomotion.run.config import resolve_config
    from evomotion.run.runner import run_study

    cfg = resolve_config(STUDY, overrides=["run.evaluator='process'"])
    with pytest.raises(InputError, match="no batch evaluation"):
        run_study(STUDY, cfg, tmp_path, quiet=True)


def test_cli_check_exit_codes(doc: dict, tmp_path: Path) -> None:
    runner = CliRunner()
    write_plan(tmp_path / "good.json", doc)
    r = runner.invoke(cli, ["check", str(tmp_path / "good.json")])
    assert r.exit_code == 0 and "ok" in r.output
    bad = _tampered(doc, lambda d: d["states"][-1]["feet"][1].__setitem__(1, 99.0))
    write_plan(tmp_path / "bad.json", bad)
    r = runner.invoke(cli, ["check", str(tmp_path / "bad.json")])
    assert r.exit_code == 1 and f"state {len(doc['states']) - 1}" in r.output


def test_experiment_row_next_to_paper_figures() -> None:
    row = run_config(QuadrupedPlanConfig(rule_set="A", start_phi=math.pi / 4),
                     SearchConfig(function=1), "a")
    assert row.stop_reason == "found" and row.check == "ok"
    assert row.paper == PAPER_FIGURES[(1, "A", "a")] == (284, 45)
    text = format_table([row])
    assert "284/45" in text and " ok" in text


def test_checker_requires_maximal_rule3_translation(doc: dict) -> None:
    j = next(i for i, s in enumerate(doc["states"]) if s["rule"] == 3)
    b0, b1 = doc["states"][j - 1]["body"], doc["states"][j]["body"]

    def shorten(d: dict) -> None:
        d["states"][j]["body"] = [b0[0] + 0.5 * (b1[0] - b0[0]), b0[1] + 0.5 * (b1[1] - b0[1]),
                                  b0[2]]

    with pytest.raises(PlanViolationError, match=f"state {j} .*stops short"):
        check_plan(_tampered(doc, shorten))


def test_set_a_cannot_walk_forward_open_empties(tmp_path: Path) -> None:
    # rule set A places no foot ahead of its hip: walking towards body +Y gets stuck
    cfg = QuadrupedPlanConfig(sense=1, rule_set="A", start_phi=math.pi / 4)
    assert run_plan(cfg, tmp_path, function=1) == 1
    assert "OPEN is empty" in (tmp_path / "log.txt").read_text()


def test_weighted_astar_run_reports_its_bound(tmp_path: Path) -> None:
    assert run_plan(SHORT, tmp_path, method="weighted-astar", weight=2.0,
                    max_expansions=60_000) == 0
    search = read_plan(tmp_path / "plan.json")["search"]
    assert search["lower_bound"] == search["cost"] / 2.0
    assert f"least cost >= {search['cost'] / 2.0:.4g}" in (tmp_path / "log.txt").read_text()
