"""Reading a 7,100 x 7,100 Moving AI map (50 MB): seconds and peak memory of ``read_map``.

Writes a random map (density 0.15, corners free) to a temporary folder and reads it in a
fresh interpreter per reader, so that ru_maxrss is the reader's own peak (minus the imports,
measured first; tracemalloc's peak, which numpy reports to, is the reader's alone, from a
second read). ``--old SRC`` also times a previous reader, e.g. from an export of commit
d61c970 (``git archive d61c970 src | tar -x -C TMP``, then ``--old TMP/src``); ``--size`` and
``--old-timeout`` keep that run bounded (the old reader is a per-character loop plus a
breadth-first search in Python).

    python3 benchmarks/bench_map_read.py [--size 7100] [--old TMP/src]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile
from pathlib import Path

import numpy as np

CHILD = """
import json, resource, sys, time, tracemalloc
import numpy, scipy.ndimage
from evomotion.studies.grid_path.maps import read_map
base = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
t = time.perf_counter()
m = read_map(sys.argv[1])
dt = time.perf_counter() - t
peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss
tracemalloc.start()
read_map(sys.argv[1])
traced = tracemalloc.get_traced_memory()[1]
print(json.dumps({"seconds": round(dt, 3), "maxrss_mib": round(peak / 1024),
                  "maxrss_before_mib": round(base / 1024),
                  "tracemalloc_peak_mib": round(traced / 2**20),
                  "shape": list(m.blocked.shape), "blocked": int(m.blocked.sum())}))
"""
WRITER = """
import sys
sys.path.insert(0, sys.argv[3])
from bench_map_read import write_random_map
from pathlib import Path
write_random_map(Path(sys.argv[1]), int(sys.argv[2]))
"""


def write_random_map(path: Path, n: int, density: float = 0.15, seed: int = 0) -> None:
    rng = np.random.default_rng(seed)
    blocked = rng.random((n, n)) < density
    blocked[-2:, :2] = blocked[:2, -2:] = False  # start bottom-left, goal top-right (file rows)
    rows = np.full((n, n + 1), ord("\n"), dtype=np.uint8)
    rows[:, :n] = np.frombuffer(b".@", np.uint8)[blocked.astype(np.uint8)]
    path.write_bytes(f"type octile\nheight {n}\nwidth {n}\nmap\n".encode() + rows.tobytes())


def _write(path: Path, n: int) -> None:
    """In a child process, so that this one stays small (ru_maxrss is inherited by children)."""
    subprocess.run([sys.executable, "-c", WRITER, str(path), str(n),
                    str(Path(__file__).parent)], check=True)


def measure(src: str | None, path: Path, timeout: float) -> dict:
    env_path = [src] if src else []
    cmd = [sys.executable, "-c", CHILD, str(path)]
    env = None
    if env_path:
        import os

        env = dict(os.environ, PYTHONPATH=os.pathsep.join(env_path))
    try:
        out = subprocess.run(cmd, capture_output=True, text=True, timeout=timeout, env=env)
    except subprocess.TimeoutExpired:
        return {"timeout_s": timeout}
    if out.returncode:
        return {"error": out.stderr.strip().splitlines()[-1:]}
    return json.loads(out.stdout)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--size", type=int, default=7100)
    ap.add_argument("--old", help="src folder of a previous evomotion to compare with")
    ap.add_argument("--old-size", type=int, default=0, help="map size for the old reader")
    ap.add_argument("--old-timeout", type=float, default=300.0)
    args = ap.parse_args()
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / f"random-{args.size}.map"
        _write(path, args.size)
        print(f"map {args.size} x {args.size}: {path.stat().st_size / 1e6:.1f} MB")
        r = measure(None, path, 600)
        print("current reader:", json.dumps(r))
        if args.old:
            old_path = path
            if args.old_size:
                old_path = Path(tmp) / f"random-{args.old_size}.map"
                _write(old_path, args.old_size)
            r = measure(args.old, old_path, args.old_timeout)
            size = args.old_size or args.size
            print(f"previous reader ({size} x {size}):", json.dumps(r))


if __name__ == "__main__":
    main()
