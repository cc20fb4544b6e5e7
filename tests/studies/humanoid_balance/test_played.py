"""The studio's view of a balance run (``StudyView.played``): the exported policy in an
unseen world, recorded as the closed loop played it; the same episode ``evomotion replay``
reports, and the 3D player's recording of it."""

from __future__ import annotations

import numpy as np
import pytest

from evomotion.api import run
from evomotion.errors import InputError
from evomotion.studies import get_study
from evomotion.studies.humanoid_balance.replay import played, replay_policy


@pytest.fixture(scope="module")
def balance_run(tmp_path_factory):
    out = tmp_path_factory.mktemp("b") / "run"
    run("humanoid-balance", {"run": {"generations": 2},
                             "algorithm": {"pop_size": 4, "top_directions": 0},
                             "problem": {"duration_s": 1.5, "eval_episodes": 1, "episodes": 1,
                                         "validate_episodes": 2,
                                         "threads": 1, "push_window_start": 0.1,
                                         "push_window_end": 0.2}}, out)
    return out


def test_played_is_the_episode_replay_reports(balance_run):
    for world, push in ((0, None), (3, 5.0)):
        ep = played(balance_run, world, push)
        summary, _ = replay_policy(balance_run, seed=0, push_ns=push) if world == 0 else \
            (None, None)
        nu = ep.ctrl.shape[1]
        assert ep.states.ndim == 2 and ep.ctrl.shape == (len(ep.states), nu)
        assert ep.frame_dt_s == pytest.approx(0.02)
        assert f"unseen world {world}" in ep.caption
        if push is not None:
            assert "a 5.00 N s push" in ep.caption
        if summary is not None:  # the same world as `evomotion replay RUN --seed 0`
            assert (ep.fall_time_s is not None) == summary["fell"]
            if summary["fell"]:
                assert ep.fall_time_s == pytest.approx(summary["fall_time_s"])
            assert np.allclose(np.linalg.norm(summary["push_ns"]),
                               float(ep.caption.split("a ")[1].split(" N s")[0]), atol=0.01)
        # up to the fall, then cut (the closed loop repeats the fallen state)
        end = len(ep.states) - 1
        assert end * ep.frame_dt_s <= (ep.fall_time_s or 1.5) + ep.frame_dt_s + 1e-9


def test_the_player_records_the_played_states_as_they_are(balance_run):
    from evomotion.studio.nao3d import record_poses

    ep = played(balance_run, 1, 5.0)
    rec = record_poses(ep, "nao", fps=25.0)
    k = np.arange(0, len(ep.states), 2)  # 20 ms control periods at 25 frames/s: every 2nd
    assert np.array_equal(rec["frame_states"], ep.states[k])
    assert rec["frame_dt_s"] == pytest.approx(0.04)
    assert rec["fell"] == (ep.fall_time_s is not None)
    assert record_poses(ep, "nao", fps=25.0) is rec  # cached by content


def test_bad_worlds_and_pushes_are_one_line(balance_run, tmp_path):
    for world, push, match in ((-1, None, "world"), (10_000, None, "world"), (0.5, None, "world"),
                               (0, -2.0, "push"), (0, float("nan"), "push")):
        with pytest.raises(InputError, match=match):
            played(balance_run, world, push)
    with pytest.raises(InputError, match="not a run folder"):
        played(tmp_path, 0, None)
    assert get_study("humanoid-balance").view.played is not None
