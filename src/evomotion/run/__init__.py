"""The run loop (session, drivers, config, evaluators, loggers, checkpoints).

The package is also the function ``evomotion.run(problem_or_study, config=None, out_dir=None,
*, preset=None, resume=False, quiet=True)``: calling it calls :func:`evomotion.api.run` (see
there). It is a callable module so that ``evomotion.run`` names the same object whether or not
a submodule such as ``evomotion.run.config`` has been imported.
"""

from __future__ import annotations

import sys
import types
from typing import Any


class _CallableModule(types.ModuleType):
    def __call__(self, *args: Any, **kwargs: Any) -> Any:
        from evomotion.api import run

        return run(*args, **kwargs)


sys.modules[__name__].__class__ = _CallableModule
