"""Memory of this machine, for the checks that refuse a run before it allocates (bottom layer:
used by ``run.limits`` and by ``sim.warp_memory`` alike)."""

from __future__ import annotations

import os


def available_bytes() -> int | None:
    """Memory available to a new allocation now (``MemAvailable`` of ``/proc/meminfo``, else
    ``sysconf``), or ``None`` when it cannot be told."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return int(line.split()[1]) * 1024
    except (OSError, ValueError, IndexError):
        pass
    try:
        return os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_AVPHYS_PAGES")
    except (AttributeError, OSError, ValueError):
        return None
