"""The console side every ``evomotion replay`` body shares (a ``.motion``, a gym, balance or
walk run): a video that could not be rendered is one note on stderr, and ``--json`` prints the
summary alone on stdout."""

from __future__ import annotations

import json
import sys
from pathlib import Path
from typing import Any


def report_replay(summary: dict[str, Any], skipped: str | None, video: Path | None,
                  json_out: bool) -> tuple[bool, Path | None]:
    """Note ``skipped`` (why no video was written) on stderr; with ``json_out`` print
    ``summary`` as JSON. Returns (whether that printed all there is to print, the video
    written: ``video``, or None where it was skipped)."""
    if skipped is not None:
        print(f"video skipped: {skipped}", file=sys.stderr)
        video = None
    if json_out:
        print(json.dumps(summary))
        return True, video
    return False, video
