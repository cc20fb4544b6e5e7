"""How fast the studio shows many runs: 200 run folders of 1,000 generations each.

One real ``functions`` run of 1,000 generations is made and copied 200 times (as real run
folders: config, stats.csv, log, checkpoints, best.json); the studio serves them and headless
Chromium (Debian's) times, from navigation start, until the runs list shows all 200 runs and
until a run page shows its 1,001 rows of curves. Also times the data layer alone.

    python benchmarks/bench_studio.py [--runs 200] [--generations 1000] [--repeats 5]
"""

from __future__ import annotations

import argparse
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "tests" / "studio"))

from studio_helpers import ARGS, CHROMIUM, TOKEN, free_port, get  # noqa: E402

from evomotion.run.config import resolve_config  # noqa: E402
from evomotion.run.runner import run_study  # noqa: E402
from evomotion.studies import get_study  # noqa: E402
from evomotion.studio import data  # noqa: E402


def make_runs(root: Path, runs: int, generations: int) -> None:
    s = get_study("functions")
    cfg = resolve_config(s, None, ["problem.dim=10", "algorithm.pop_size=20",
                                   f"run.generations={generations - 1}",
                                   "run.checkpoint_every=100"])
    first = root / "functions-000"
    run_study(s, cfg, first, quiet=True)
    for i in range(1, runs):
        shutil.copytree(first, root / f"functions-{i:03d}")


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=200)
    ap.add_argument("--generations", type=int, default=1000)
    ap.add_argument("--repeats", type=int, default=5)
    a = ap.parse_args()
    from playwright.sync_api import sync_playwright

    root = Path(tempfile.mkdtemp(prefix="studio-bench-"))
    try:
        make_runs(root, a.runs, a.generations)
        t = time.perf_counter()
        n = len(data.list_runs(root))
        t_list = time.perf_counter() - t
        print(f"data layer: list_runs of {n} runs {t_list * 1e3:.1f} ms")
        port = free_port()
        env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
        env["EVOMOTION_STUDIO_TOKEN"] = TOKEN
        proc = subprocess.Popen([sys.executable, "-m", "evomotion.cli", "studio", str(root),
                                 "--port", str(port)], env=env)
        base = f"http://127.0.0.1:{port}"
        for _ in range(200):
            try:
                if get(f"{base}/?token={TOKEN}")[0] == 200:
                    break
            except OSError:
                time.sleep(0.2)
        list_s, page_s = [], []
        with sync_playwright() as p:
            browser = p.chromium.launch(executable_path=CHROMIUM, args=ARGS)
            pg = browser.new_page(viewport={"width": 1300, "height": 1000})
            pg.goto(f"{base}/?token={TOKEN}")
            for _ in range(a.repeats):
                t = time.perf_counter()
                pg.goto(f"{base}/")
                pg.wait_for_function(f"document.querySelector('.runs-count') && "
                                     f"document.querySelector('.runs-count').innerText == "
                                     f"'{a.runs} runs' && document.querySelectorAll("
                                     f"'.runs-table tbody tr').length > 0")
                list_s.append(time.perf_counter() - t)
                t = time.perf_counter()
                pg.goto(f"{base}/run?name=functions-{a.runs // 2:03d}")
                pg.wait_for_function(f"document.querySelector('.run-summary') && document."
                                     f"querySelector('.run-summary').innerText.includes("
                                     f"'{a.generations} rows') && document.querySelector("
                                     f"'.fitness-chart canvas')")
                page_s.append(time.perf_counter() - t)
            browser.close()
        proc.terminate()
        proc.wait(10)
        print(f"runs list ({a.runs} runs x {a.generations} generations): median "
              f"{statistics.median(list_s):.3f} s, max {max(list_s):.3f} s "
              f"(target < 2 s)")
        print(f"run page ({a.generations} rows): median {statistics.median(page_s):.3f} s, "
              f"max {max(page_s):.3f} s (target < 1 s)")
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
