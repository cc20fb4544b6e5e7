"""Registry of studies: name -> ``"module:attribute"`` of a :class:`~.base.Study`.

Entries are imported lazily so that ``evomotion studies`` stays fast and a study's heavy
dependencies load only when it is used.
"""

from __future__ import annotations

import importlib

from evomotion.core.registry import lookup
from evomotion.errors import InputError
from evomotion.studies.base import Study

STUDIES: dict[str, str] = {
    "grid-path": "evomotion.studies.grid_path.study:STUDY",
    "functions": "evomotion.studies.functions.study:STUDY",
    "humanoid-step": "evomotion.studies.humanoid_step.study:STUDY",
    "humanoid-walk": "evomotion.studies.humanoid_omniwalk.study:STUDY",
    "humanoid-walk-open-loop": "evomotion.studies.humanoid_walk.study:STUDY",
    "humanoid-repertoire": "evomotion.studies.humanoid_repertoire.study:STUDY",
    "arm-ik": "evomotion.studies.arm_ik.study:STUDY",
    "biped-kick": "evomotion.studies.biped_kick.study:STUDY",
    "quadruped-plan": "evomotion.studies.quadruped_plan.study:STUDY",
    "gym": "evomotion.studies.gym.study:STUDY",
    "humanoid-balance": "evomotion.studies.humanoid_balance.study:STUDY",
}

#: Old study names -> the names now: commands with an old name keep working (run folders
#: are read under the name now too: :data:`evomotion.run.config.RENAMED_STUDIES`). The
#: packages keep their names: ``humanoid_omniwalk`` holds ``humanoid-walk``,
#: ``humanoid_walk`` holds ``humanoid-walk-open-loop``.
OLD_STUDY_NAMES: dict[str, str] = {"humanoid-omniwalk": "humanoid-walk"}


def get_study(name: str) -> Study:
    """The registered study ``name`` (or its old name, :data:`OLD_STUDY_NAMES`; its module
    is imported now); an unknown name is an :class:`~evomotion.errors.InputError` listing
    the available ones."""
    target = lookup(STUDIES, "study", OLD_STUDY_NAMES.get(name, name))
    module, attr = target.split(":")
    return getattr(importlib.import_module(module), attr)


def study_with_preset(name: str, preset: str | None) -> tuple[Study, str | None]:
    """The study and preset a new run of ``name --preset preset`` runs: a preset that is
    another study (``Study.preset_studies``: ``humanoid-walk --preset open-loop``) runs that
    study with its defaults."""
    study = get_study(name)
    if preset is not None and preset in study.preset_studies:
        return get_study(study.preset_studies[preset]), None
    if preset is not None and preset not in study.presets:
        for key, target in study.preset_studies.items():  # a preset of the preset's study
            if preset in get_study(target).presets:
                raise InputError(f"--preset: {preset!r} is a preset of {target} (the "
                                 f"{key!r} preset of {study.name}): run {target} "
                                 f"--preset {preset}")
    return study, preset


def all_studies() -> list[Study]:
    """Every registered study, in :data:`STUDIES` order."""
    return [get_study(n) for n in STUDIES]
