"""Build the API reference of evomotion from its docstrings with pdoc.

    python scripts/api_docs.py [OUT_DIR]     # default build/api; open OUT_DIR/evomotion.html

The reference covers the public API (``evomotion``: the run loop, problems, optimizers,
studies) and the packages below it (core, run, sim, studies, studio).
"""

from __future__ import annotations

import os
import sys
from pathlib import Path


def build(out: Path) -> list[Path]:
    """Write the HTML reference into ``out``; returns the pages written."""
    os.environ.setdefault("MUJOCO_GL", "osmesa")
    import pdoc
    import pdoc.render

    pdoc.render.configure(docformat="restructuredtext", show_source=False,
                          footer_text="evomotion API")
    # "evomotion" documents what its __all__ names (the run package among them); the other
    # packages are named here
    modules = ["evomotion", "evomotion.api", "evomotion.core", "evomotion.errors",
               "evomotion.sim", "evomotion.studies", "!evomotion.sim.warp_kernels"]
    pdoc.pdoc(*modules, output_directory=out)
    return sorted(out.rglob("*.html"))


if __name__ == "__main__":
    pages = build(Path(sys.argv[1] if len(sys.argv) > 1 else "build/api"))
    print(f"{len(pages)} pages -> {pages[0].parent if pages else '-'}")
