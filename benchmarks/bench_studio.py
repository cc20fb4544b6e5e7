"""How fast the studio is (issue 35's figures): the runs list with 1,000 run folders, a run
page of 10,000 generations, and the 3D player's frames per second on a 20 s motion.

One real ``functions`` run of ``--generations`` generations is made and copied ``--runs``
times (as real run folders: config, stats.csv, log, checkpoints, best.json), plus one run of
``--long`` generations; the studio serves them and headless Chromium (Debian's, software
WebGL: ``--disable-gpu``) times, from navigation start, until the runs list shows every run
and until the long run's page shows all its rows of curves. The player: a 20 s NAO motion (arms
waving) in a ``humanoid-step`` run folder; after it starts, for ``--seconds`` s, the frames the
scene renders (three.js ``renderer.info.render.frame``), the poses the player sets, and the
motion time it advances against the wall clock. Also times the data layer alone.

    python benchmarks/bench_studio.py [--runs 1000] [--generations 100] [--long 10000]
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
    """``runs`` copies of one real run (the first: ``functions-0000``)."""
    s = get_study("functions")
    cfg = resolve_config(s, None, ["problem.dim=10", "algorithm.pop_size=20",
                                   f"run.generations={generations - 1}",
                                   "run.checkpoint_every=100"])
    first = root / "functions-0000"
    run_study(s, cfg, first, quiet=True)
    for i in range(1, runs):
        shutil.copytree(first, root / f"functions-{i:04d}")


def make_long_run(root: Path, generations: int) -> None:
    s = get_study("functions")
    cfg = resolve_config(s, None, ["problem.dim=10", "algorithm.pop_size=20",
                                   f"run.generations={generations - 1}",
                                   "run.checkpoint_every=1000"])
    run_study(s, cfg, root / "long-run", quiet=True)


def make_motion_run(root: Path, seconds: float = 20.0) -> None:
    """A humanoid-step run folder holding a ``seconds`` s motion (arms waving)."""
    import numpy as np

    from evomotion.sim.motion import Motion, format_motion
    from evomotion.sim.robots import nao

    s = get_study("humanoid-step")
    run_study(s, resolve_config(s, None, [*s.smoke, "run.generations=1", "run.videos=false"]),
              root / "player", quiet=True)
    t = np.arange(0, seconds * 1000 + 1, 40, dtype=np.int64)
    q = np.tile(nao.pose_vector(), (len(t), 1))
    arms = [i for i, n in enumerate(nao.JOINTS) if n.endswith("ShoulderPitch")]
    q[:, arms] += 0.8 * np.sin(2 * np.pi * t[:, None] / 2000.0)
    (root / "player" / "wave-20s.motion").write_text(
        format_motion(Motion(nao.JOINTS, t, q)), encoding="utf-8")


PLAYER_PROBE = """() => { const p = Object.values(window.evoPlayers || {})
  .find(q => q.duration > 19);
  return p ? [p.comp.renderer.info.render.frame, p.applied, p.t, performance.now()] : null }"""


def player_rate(pg, base: str, seconds: float) -> dict:
    pg.goto(f"{base}/run?name=player")
    pg.wait_for_selector(".nao-scene")
    pg.locator(".motion-pick").click()
    pg.get_by_role("option", name="wave-20s.motion").click()
    pg.wait_for_function("Object.values(window.evoPlayers || {}).some(q => q.duration > 19 "
                         "&& q.t > 0.5)", timeout=120000)
    a = pg.evaluate(PLAYER_PROBE)
    pg.wait_for_timeout(seconds * 1000)
    b = pg.evaluate(PLAYER_PROBE)
    wall = (b[3] - a[3]) / 1000
    advanced = (b[2] - a[2]) % 20.0  # the motion loops
    return {"rendered_fps": (b[0] - a[0]) / wall, "poses_per_s": (b[1] - a[1]) / wall,
            "real_time": advanced / wall}


def measure(a, base: str, sync_playwright) -> tuple[list, list, list]:
    """Runs list and run page times (``--repeats`` each) and two player measurements."""
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
                                 f"'{a.runs + 2} runs' && document.querySelectorAll("
                                 f"'.runs-table tbody tr').length > 0")
            list_s.append(time.perf_counter() - t)
            t = time.perf_counter()
            pg.goto(f"{base}/run?name=long-run")
            pg.wait_for_function(f"document.querySelector('.run-summary') && document."
                                 f"querySelector('.run-summary').innerText.includes("
                                 f"'{a.long} rows') && document.querySelector("
                                 f"'.fitness-chart canvas')")
            page_s.append(time.perf_counter() - t)
        rates = [player_rate(pg, base, a.seconds) for _ in range(2)]
        browser.close()
    return list_s, page_s, rates


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--runs", type=int, default=1000)
    ap.add_argument("--generations", type=int, default=100)
    ap.add_argument("--long", type=int, default=10000)
    ap.add_argument("--repeats", type=int, default=5)
    ap.add_argument("--seconds", type=float, default=8.0)
    a = ap.parse_args()
    from playwright.sync_api import sync_playwright

    root = Path(tempfile.mkdtemp(prefix="studio-bench-"))
    try:
        make_runs(root, a.runs, a.generations)
        make_long_run(root, a.long)
        make_motion_run(root)
        t = time.perf_counter()
        n = len(data.list_runs(root))
        t_list = time.perf_counter() - t
        print(f"data layer: list_runs of {n} runs {t_list * 1e3:.1f} ms")
        port = free_port()
        env = {k: v for k, v in os.environ.items() if not k.startswith("PYTEST")}
        env["EVOMOTION_STUDIO_TOKEN"] = TOKEN
        proc = subprocess.Popen([sys.executable, "-m", "evomotion.cli", "studio", str(root),
                                 "--port", str(port)], env=env)
        try:
            list_s, page_s, rates = measure(a, f"http://127.0.0.1:{port}", sync_playwright)
        finally:
            proc.terminate()
            proc.wait(10)
        print(f"runs list ({a.runs + 2} runs): median {statistics.median(list_s):.3f} s, "
              f"max {max(list_s):.3f} s (target < 1 s)")
        print(f"run page ({a.long} rows): median {statistics.median(page_s):.3f} s, "
              f"max {max(page_s):.3f} s (target < 1 s)")
        for r in rates:
            print(f"3D player, 20 s motion: {r['rendered_fps']:.1f} frames rendered/s, "
                  f"{r['poses_per_s']:.1f} poses set/s, {r['real_time']:.2f}x real time "
                  "(target >= 25 frames/s)")
    finally:
        shutil.rmtree(root, ignore_errors=True)


if __name__ == "__main__":
    main()
