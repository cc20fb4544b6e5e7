"""Registry of studies: name -> ``"module:attribute"`` of a :class:`~.base.Study`.

Entries are imported lazily so that ``evomotion studies`` stays fast and a study's heavy
dependencies load only when it is used.
"""

from __future__ import annotations

import importlib

from evomotion.core.registry import lookup
from evomotion.studies.base import Study

STUDIES: dict[str, str] = {
    "grid-path": "evomotion.studies.grid_path.study:STUDY",
    "functions": "evomotion.studies.functions.study:STUDY",
    "humanoid-step": "evomotion.studies.humanoid_step.study:STUDY",
    "humanoid-walk": "evomotion.studies.humanoid_walk.study:STUDY",
    "humanoid-repertoire": "evomotion.studies.humanoid_repertoire.study:STUDY",
    "arm-ik": "evomotion.studies.arm_ik.study:STUDY",
    "biped-kick": "evomotion.studies.biped_kick.study:STUDY",
    "quadruped-plan": "evomotion.studies.quadruped_plan.study:STUDY",
    "gym": "evomotion.studies.gym.study:STUDY",
    "humanoid-balance": "evomotion.studies.humanoid_balance.study:STUDY",
    "humanoid-omniwalk": "evomotion.studies.humanoid_omniwalk.study:STUDY",
}


def get_study(name: str) -> Study:
    """The registered study ``name`` (its module is imported now); an unknown name is an
    :class:`~evomotion.errors.InputError` listing the available ones."""
    target = lookup(STUDIES, "study", name)
    module, attr = target.split(":")
    return getattr(importlib.import_module(module), attr)


def all_studies() -> list[Study]:
    """Every registered study, in :data:`STUDIES` order."""
    return [get_study(n) for n in STUDIES]
