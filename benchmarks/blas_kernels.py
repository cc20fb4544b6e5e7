"""Does a run's result depend on the BLAS kernels OpenBLAS picks for the CPU? The same study,
seed and settings run in fresh processes told ``OPENBLAS_CORETYPE`` (as another CPU would
make OpenBLAS choose): the first generation's largest difference in ``stats.csv`` and whether
the run's files are byte for byte the same (``physics.json`` aside, which records the kernels).

    python benchmarks/blas_kernels.py [--study humanoid-walk] [--cores Haswell Sandybridge]
        [--generations 2] [--set KEY=VALUE ...]
"""

from __future__ import annotations

import argparse
import csv
import os
import subprocess
import sys
import tempfile
from pathlib import Path


def run(study: str, core: str, out: Path, sets: list[str]) -> None:
    args = [a for kv in sets for a in ("--set", kv)]
    subprocess.run([sys.executable, "-m", "evomotion.cli", "run", study, "--out", str(out),
                    "-q", *args], check=True, env={**os.environ, "OPENBLAS_CORETYPE": core})


def first_row(path: Path) -> dict[str, float]:
    with open(path, newline="") as f:
        row = next(csv.DictReader(f))
    return {k: float(v) for k, v in row.items() if k not in ("wall_s", "evals_per_s")}


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--study", default="humanoid-walk")
    ap.add_argument("--cores", nargs="+", default=["Haswell", "Sandybridge"])
    ap.add_argument("--generations", type=int, default=2)
    ap.add_argument("--set", dest="sets", action="append", default=[])
    a = ap.parse_args()
    sets = [f"run.generations={a.generations}", "run.seed=0", "run.videos=false", *a.sets]
    with tempfile.TemporaryDirectory() as tmp:
        outs = {c: Path(tmp) / c for c in a.cores}
        for core, out in outs.items():
            run(a.study, core, out, sets)
        base, rows = a.cores[0], {c: first_row(o / "stats.csv") for c, o in outs.items()}
        files = sorted(p.relative_to(outs[base]) for p in outs[base].rglob("*")
                       if p.is_file() and p.name not in ("physics.json", "log.txt", "stats.csv",
                                                         "run.lock", "latest.json")
                       and p.suffix != ".json" or p.name == "policy.json")
        for core in a.cores[1:]:
            diff = max(abs(rows[core][k] - rows[base][k]) for k in rows[base])
            same = [f for f in files if (outs[core] / f).is_file()
                    and (outs[core] / f).read_bytes() == (outs[base] / f).read_bytes()]
            differ = ", ".join(str(f) for f in files if f not in same)
            print(f"{a.study}: {core} against {base}: generation 0's stats differ by at most "
                  f"{diff:.3g}; {len(same)} of {len(files)} files byte for byte"
                  + (f" ({differ} differ)" if differ else ""))
    return 0


if __name__ == "__main__":
    sys.exit(main())
