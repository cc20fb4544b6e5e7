"""Reading a ``humanoid-repertoire`` run folder without trusting it.

Every command that takes a repertoire (``pick``, ``walk-to``, ``export``, the kick's ``play
--walk``) goes through here:

- :func:`repertoire_run`: the folder (or its ``repertoire/``) is a run of this study, read
  from its ``config.toml``; another study's run is refused, naming that study;
- :func:`load_index`: ``repertoire/index.json`` of such a run, read with the bounded JSON
  reader and checked entry by entry (:func:`evomotion.sim.repertoire.read_index`: each
  step's measured ``dx_m``/``dy_m`` within +-1 m, ``dtheta_deg`` within +-180 degrees, its
  ``objective`` within +-1000);
- :func:`load_archive`: ``archive.npz`` through the run loop's reader (the npz reader that
  checks every declared shape before allocating, then every field).

Every failure is one :class:`~evomotion.errors.InputError` line naming the file or folder.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from evomotion.errors import InputError

STUDY = "humanoid-repertoire"
INDEX = "index.json"


def repertoire_run(path: str | Path, option: str = "RUN") -> Path:
    """The run folder named by ``path`` (a ``humanoid-repertoire`` run folder or its
    ``repertoire/``), checked by its ``config.toml``."""
    from evomotion.run.config import run_of_study

    return run_of_study(path, STUDY, option, subfolder="repertoire")


def run_config(run: Path) -> Any:
    """The resolved :class:`~evomotion.run.config.Config` of the run folder ``run``."""
    from evomotion.run.config import config_from_dict, config_from_run_dir
    from evomotion.studies import get_study

    name, raw = config_from_run_dir(run)
    return config_from_dict(get_study(name), raw)


def load_index(run: str | Path, option: str = "RUN") -> tuple[Path, dict]:
    """``(repertoire folder, index)`` of the repertoire run ``run``: the run checked by
    :func:`repertoire_run`, its index read and checked by
    :func:`evomotion.sim.repertoire.read_index` (bounded JSON, every entry's ranges)."""
    from evomotion.sim.repertoire import read_index

    return read_index(repertoire_run(run, option))


def load_archive(path: Path) -> Any:
    """The run's ``archive.npz`` (:class:`~evomotion.run.archive_file.ArchiveFile`; its
    declared shapes are checked before any array is allocated)."""
    from evomotion.run.archive_file import read_archive

    if not path.exists():
        raise InputError(f"{path}: no such file (a {STUDY} run writes archive.npz at its "
                         "checkpoints)")
    return read_archive(path)
