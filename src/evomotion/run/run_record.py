"""What a run runs on, recorded in its run folder through the study's ``run_record`` hook.

The run loop knows nothing of physics: a study hands it a
:class:`~evomotion.run.contracts.RunRecord` (e.g. ``physics.json``, the MuJoCo backend and
what it guarantees, :mod:`evomotion.studies.run_hooks`), which is written at every start and
resume; its notes (a non-CPU backend; a resume on something else than the run started on,
which is then not bit-identical) go to the run log.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

from evomotion.errors import InputError
from evomotion.outfile import atomic_write_text
from evomotion.run.contracts import RunStudy
from evomotion.run.runlog import RunLog
from evomotion.textio import read_json


def record_run(study: RunStudy, problem: Any, out_dir: Path, resume: bool,
               log: RunLog) -> None:
    """The study's record of what the run runs on (its ``run_record`` hook, e.g.
    ``physics.json``), written in the run folder at every start; its note (e.g. a non-CPU
    backend) and, on resume, a change from the record the folder holds, are logged."""
    make = study.run_record
    rec = make(problem) if make is not None else None
    if rec is None:
        return
    now = rec.record()
    note = rec.start_note(now)
    if note:
        log(note)
    path = out_dir / rec.name
    if resume and path.exists():
        try:
            before = read_json(path, rec.name, 1 << 20, finite=False)
        except InputError:
            before = None
        note = rec.resume_note(before, now)
        if note:
            log(note)
    atomic_write_text(path, rec.text(now))
