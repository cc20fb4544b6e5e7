"""The typed run counters: a checkpoint's ``counters`` object read and written unchanged."""

from __future__ import annotations

import json

from evomotion.run.counters import Counters

#: the counters of a checkpoint as the untyped loop wrote them (key order included)
OLD = {"generation": 7, "evaluations": 192, "wall_s": 1.25, "failed_total": 3,
       "hist_best": [-1.0, -2.5], "hist_mean": [0.5, 0.25], "best_metrics": {"norm": 1.5},
       "stats_offset": 812, "log_offset": 140, "history_offset": 0, "stop_reason": None}


def test_an_old_checkpoints_counters_are_written_back_identically():
    for doc in (OLD, {**OLD, "stop_reason": "generations", "finished": False},
                {k: v for k, v in OLD.items() if k != "stop_reason"}):
        back = Counters.from_json(json.loads(json.dumps(doc))).to_json()
        assert json.dumps(back) == json.dumps(doc)


def test_a_run_folder_older_than_the_history_offset_resumes():
    doc = {k: v for k, v in OLD.items() if k != "history_offset"}
    c = Counters.from_json(doc)
    assert c.history_offset == 0 and c.finished is None and c.stop_reason is None


def test_a_new_runs_first_snapshot_has_no_stop_reason():
    c = Counters(stats_offset=10, log_offset=20)
    assert list(c.to_json()) == ["generation", "evaluations", "wall_s", "failed_total",
                                 "hist_best", "hist_mean", "best_metrics", "stats_offset",
                                 "log_offset", "history_offset"]
    assert c.to_json()["generation"] == -1
