"""The search settings moved from ``[problem]`` to ``[algorithm]`` (issue 32): the old keys
still work (``--set``, files, a run folder written before the move resumes), with one note
per moved key; the old and the new key together are one line."""

from __future__ import annotations

import csv
import json
import logging
import math
from pathlib import Path

import pytest

from evomotion.errors import InputError
from evomotion.run.config import config_from_dict, resolve_config
from evomotion.run.resume import resume_config
from evomotion.run.runner import run_study
from evomotion.studies import get_study
from evomotion.studies.quadruped_plan.plans.search_config import SEARCH_KEYS

STUDY = get_study("quadruped-plan")
SHORT = ["problem.start_phi=0.0", "problem.goal_x=0.0", "problem.goal_y=-7.0",
         "problem.gif_max_frames=3", "run.seed=1", "run.checkpoint_every=1",
         "algorithm.batch_expansions=50"]
TIMING = {"wall_s", "evals_per_s"}


def _notes(caplog: pytest.LogCaptureFixture) -> list[str]:
    return [r.getMessage() for r in caplog.records if r.name == "evomotion.run.moved_keys"]


def test_old_keys_read_at_their_new_place_with_one_note(caplog) -> None:
    new = resolve_config(STUDY, None, ["algorithm.method=astar", "algorithm.weight=2.0",
                                       "algorithm.max_expansions=3000"])
    assert _notes(caplog) == []
    old = resolve_config(STUDY, None, ["problem.method=astar", "problem.weight=2.0",
                                       "problem.max_expansions=3000"])
    assert old == new and old.algorithm.method == "astar"
    assert _notes(caplog) == ["note: " + "; ".join(
        f"problem.{k} is the old name of algorithm.{k}" for k in ("method", "weight",
                                                                  "max_expansions"))]


def test_the_paper_preset_sets_the_search_in_algorithm() -> None:
    cfg = resolve_config(STUDY, None, preset="paper")
    assert (cfg.algorithm.method, cfg.algorithm.function, cfg.problem.rule_set) == \
        ("best-first", 1, "A")
    # an old key over the preset's new one is another source: it wins, no clash
    assert resolve_config(STUDY, None, ["problem.function=2"], preset="paper"
                          ).algorithm.function == 2


def test_receding_moves_only_the_heuristic_gain(caplog) -> None:
    raw = {"algorithm": {"name": "receding"},
           "problem": {"world": "corridor", "heuristic_gain": "sampled", "method": "astar"}}
    cfg = config_from_dict(STUDY, raw)
    assert cfg.algorithm.heuristic_gain == "sampled"
    (notes,) = _notes(caplog)
    assert "problem.heuristic_gain is the old name of algorithm.heuristic_gain" in notes
    dropped = ("problem.method is the old name of algorithm.method, a setting that "
               "algorithm.name = 'receding' does not have (ignored)")
    assert dropped in notes
    with pytest.raises(InputError, match="unknown key 'algorithm.method'"):
        resolve_config(STUDY, None, ["algorithm.name=receding", "algorithm.method=astar"])


def test_both_places_in_one_source_is_one_line(tmp_path: Path) -> None:
    f = tmp_path / "c.toml"
    f.write_text('[problem]\nmethod = "astar"\n[algorithm]\nmethod = "astar"\n')
    with pytest.raises(InputError) as e:
        resolve_config(STUDY, f)
    assert str(e.value) == ("problem.method and algorithm.method: the same setting under its "
                            "old and its new name; give only algorithm.method")
    with pytest.raises(InputError, match="^problem.k1 and algorithm.k1: "):
        config_from_dict(STUDY, {"problem": {"k1": 1.0}, "algorithm": {"k1": 1.0}})


def _to_old_layout(run: Path) -> None:
    """Rewrite a run folder as the code before the move wrote it: the search keys in
    ``[problem]`` of config.toml and in the checkpoints' recorded config."""
    import tomllib

    import tomli_w

    raw = tomllib.loads((run / "config.toml").read_text())
    for k in SEARCH_KEYS:
        raw["problem"][k] = raw["algorithm"].pop(k)
    (run / "config.toml").write_text(tomli_w.dumps(raw))
    for ck in (run / "checkpoints").glob("gen-*.json"):
        meta = json.loads(ck.read_text())
        for k in SEARCH_KEYS:
            meta["config"][f"problem.{k}"] = meta["config"].pop(f"algorithm.{k}")
        ck.write_text(json.dumps(meta))
    assert "[problem]\nstart_x" in (run / "config.toml").read_text()


def _stats(run: Path) -> list[dict]:
    rows = csv.DictReader((run / "stats.csv").read_text().splitlines())
    return [{k: v for k, v in r.items() if k not in TIMING} for r in rows]


def test_a_run_folder_of_the_old_layout_resumes_to_the_same_plan(tmp_path: Path,
                                                                 caplog) -> None:
    sets = [*SHORT, "algorithm.method=weighted-astar", "algorithm.weight=2.0",
            "algorithm.batch_expansions=5"]
    whole = tmp_path / "whole"
    assert run_study(STUDY, resolve_config(STUDY, None, sets), whole, quiet=True
                     ).exit_code == 0
    assert len(_stats(whole)) > 3
    cut = tmp_path / "cut"
    assert run_study(STUDY, resolve_config(STUDY, None, [*sets, "run.generations=2"]), cut,
                     quiet=True).exit_code == 1  # stopped by the limit: no plan yet
    _to_old_layout(cut)
    caplog.clear()
    study, cfg = resume_config(cut, None, {"run.generations": 1_000_000},
                               resolve=get_study)
    assert cfg.algorithm.method == "weighted-astar" and cfg.algorithm.weight == 2.0
    (note,) = _notes(caplog)  # one line naming every moved key
    assert note.count("is the old name of") == len(SEARCH_KEYS)
    assert run_study(study, cfg, cut, quiet=True, resume=True).exit_code == 0
    a, b = (json.loads((d / "plan.json").read_text()) for d in (whole, cut))
    a["search"].pop("seconds"), b["search"].pop("seconds")
    assert a == b and _stats(whole) == _stats(cut)
    assert math.isfinite(b["search"]["lower_bound"])


def test_an_old_record_with_another_search_is_refused(tmp_path: Path) -> None:
    run = tmp_path / "run"
    cfg = resolve_config(STUDY, None, [*SHORT, "run.generations=1"])
    run_study(STUDY, cfg, run, quiet=True)
    _to_old_layout(run)
    for ck in (run / "checkpoints").glob("gen-*.json"):
        meta = json.loads(ck.read_text())
        meta["config"]["problem.function"] = 1
        ck.write_text(json.dumps(meta))
    logging.getLogger("evomotion.run.moved_keys").setLevel(logging.ERROR)
    try:
        study, cfg = resume_config(run, None, {"run.generations": 10}, resolve=get_study)
        with pytest.raises(InputError, match="resume cannot change algorithm.function"):
            run_study(study, cfg, run, quiet=True, resume=True)
    finally:
        logging.getLogger("evomotion.run.moved_keys").setLevel(logging.NOTSET)
