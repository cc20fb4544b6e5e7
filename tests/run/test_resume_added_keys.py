"""A run folder written before a config key existed still resumes when the key is at its
default (the results cannot differ); at another value the resume is refused, naming it."""

from __future__ import annotations

import json

import pytest

from evomotion.errors import InputError
from evomotion.run.config import resolve_config
from evomotion.run.faults import fault_at
from evomotion.run.runner import run_study
from evomotion.studies import get_study


def _strip_key(out, key: str) -> None:
    for path in (out / "checkpoints").glob("*.json"):
        meta = json.loads(path.read_text())
        if "config" not in meta:
            continue
        meta["config"].pop(key)
        path.write_text(json.dumps(meta))


def test_added_key_at_its_default_resumes(tmp_path):
    s = get_study("humanoid-step")
    over = [*s.smoke, "run.generations=2", "run.checkpoint_every=1", "run.wall_seconds=0"]
    cfg = resolve_config(s, None, over)
    with fault_at(1, "interrupt"):
        run_study(s, cfg, tmp_path / "r", quiet=True)
    _strip_key(tmp_path / "r", "problem.backend")  # as written before the key existed
    res = run_study(s, cfg, tmp_path / "r", quiet=True, resume=True)
    assert res.generation == 2


def test_added_key_at_another_value_is_refused(tmp_path):
    s = get_study("humanoid-step")
    over = [*s.smoke, "run.generations=2", "run.checkpoint_every=1", "run.wall_seconds=0"]
    with fault_at(1, "interrupt"):
        run_study(s, resolve_config(s, None, over), tmp_path / "r", quiet=True)
    _strip_key(tmp_path / "r", "problem.batch_rollouts")
    changed = resolve_config(s, None, [*over, "problem.batch_rollouts=7"])
    with pytest.raises(InputError, match="resume cannot change problem.batch_rollouts"):
        run_study(s, changed, tmp_path / "r", quiet=True, resume=True)
