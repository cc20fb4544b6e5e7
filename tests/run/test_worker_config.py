"""Evaluator workers build a one-core problem through the config's ``for_worker()`` hook."""

from __future__ import annotations

import dataclasses

import pytest

from evomotion.run.config import resolve_config
from evomotion.run.evaluators import worker_config
from evomotion.studies import get_study
from evomotion.studies.biped_kick.problem import KickConfig
from evomotion.studies.humanoid_step.problem import HumanoidStepConfig


@pytest.mark.parametrize("study,field", [("biped-kick", "nthread"),
                                         ("humanoid-step", "threads")])
def test_study_default_worker_config_gets_one_thread(study, field):
    cfg = resolve_config(get_study(study), None, []).problem
    assert getattr(cfg, field) == 0  # all cores in a serial run
    assert getattr(worker_config(cfg), field) == 1


def test_explicit_thread_counts_are_kept():
    assert worker_config(KickConfig(nthread=3)).nthread == 3
    assert worker_config(HumanoidStepConfig(threads=2)).threads == 2
    cfg = HumanoidStepConfig(intervals=5)
    assert worker_config(cfg) == dataclasses.replace(cfg, threads=1)


def test_config_without_hook_is_unchanged():
    @dataclasses.dataclass(frozen=True)
    class Plain:
        threads: int = 0  # a field of that name alone no longer changes anything

    cfg = Plain()
    assert worker_config(cfg) is cfg
    assert worker_config(None) is None
