"""The walker's progress test: no livelock runs to the 400-replan limit.

On worlds it had never seen, rule set A used to livelock: after a dead end a leg flipped
between rules 5 and 9 (or the body stepped back and forward) for hundreds of moves until
the replan limit, because the "stuck" test counted only replans without an applicable move.
The worlds here are drawn from seeds (:mod:`qp_worldgen`); the two walks below reproduced
the livelock before the progress test (``failed: 400 replans``, 705 and 438 states).
"""

from __future__ import annotations

from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
from qp_worldgen import random_field

from evomotion.studies.quadruped_plan.missions.mission import (
    Mission,
    ReplanSettings,
    run_mission,
)
from evomotion.studies.quadruped_plan.rules.model import QuadrupedModel
from evomotion.studies.quadruped_plan.worlds.world import read_world

TINY = Path(__file__).parents[1] / "data" / "tiny.world"
MODEL = QuadrupedModel()


def _field(tmp_path: Path, seed: int) -> Mission:
    p = tmp_path / f"field{seed}.world"
    p.write_text(random_field(seed))
    return Mission(read_world(p), MODEL, "A")


def test_the_worlds_are_drawn_from_their_seeds():
    assert random_field(26) == random_field(26) != random_field(9)
    assert random_field(26).startswith("name field26\nbounds -6 -12 36 12\n")


@pytest.mark.parametrize(("seed", "walk", "rules"), [
    (26, 1, ("5 x", "9 x")),  # the rear-left leg flips between rules 5 and 9
    (9, 1, ("2 x", "32 x")),  # a step back (32), a step forward (2), round and round
])
def test_a_livelock_on_an_unseen_world_ends_early_with_its_reason(tmp_path, seed, walk, rules):
    m = _field(tmp_path, seed)
    st = run_mission(m, np.random.default_rng(walk))
    assert st.done != "failed: 400 replans" and st.replans < 300, st.done
    assert st.done.startswith("failed: no progress (100 transitions without getting 0.5 "
                              "units closer to the goal along the route, also with 8,000 "
                              "expansions per replan;"), st.done
    assert all(r in st.done for r in rules), st.done


def _mission(**settings) -> Mission:
    return Mission(read_world(TINY), MODEL, "A", settings=ReplanSettings(**settings))


def _moves(state, rule: int, n: int, dy: float = 0.0):
    """``state`` after ``n`` transitions of ``rule`` that move the body by ``dy`` in all."""
    real = list(state.real)
    real[1] += dy
    rows = tuple({"values": real, "rule": rule, "event": "", "target": [0.0, 0.0]}
                 for _ in range(n))
    return replace(state, real=tuple(real), path=(*state.path, *rows))


def test_the_count_escalates_then_fails_and_restarts_on_progress_or_a_new_world():
    m = _mission(progress_transitions=6, escalation=4)
    s0 = m.start()
    s1 = m.progress(s0, _moves(s0, 5, 4))
    assert (s1.stalled, s1.escalated, s1.done) == (4, False, "")
    s2 = m.progress(s1, _moves(s1, 9, 2))  # 6 without progress: replan with 4x
    assert (s2.stalled, s2.escalated, s2.done) == (0, True, "")
    s3 = m.progress(s2, _moves(s2, 5, 6))
    assert s3.done.startswith("failed: no progress (6 transitions") and "5 x" in s3.done
    assert "also with 3,200 expansions per replan" in s3.done
    step = _moves(s2, 3, 1)
    x, y = m.route(s0).path(0.0, 0.0)[4]  # 1.5 units along the route
    back = m.progress(s2, replace(step, real=(x, y, *step.real[2:])))
    assert (back.stalled, back.escalated) == (0, False) and back.progress_best < s0.progress_best
    seen = m.progress(s1, replace(_moves(s1, 9, 5), revealed=(0,)))  # the world changed
    assert (seen.stalled, seen.escalated) == (0, False)
    off = _mission(progress_transitions=0)
    t0 = off.start()
    assert off.progress(t0, _moves(t0, 5, 50)).done == ""


def test_the_progress_state_survives_a_checkpoint():
    from evomotion.studies.quadruped_plan.missions.driver import _from_json, _to_json

    m = _mission(progress_transitions=6)
    s = m.progress(m.start(), _moves(m.start(), 5, 3))
    s = replace(s, escalated=True)
    assert _from_json(_to_json(s)) == s
    old = _to_json(s)
    for key in ("progress_best", "stalled", "escalated"):  # a checkpoint of an older version
        old.pop(key)
    assert _from_json(old).stalled == 0
