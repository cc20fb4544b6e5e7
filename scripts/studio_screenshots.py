"""Screenshots of the studio's views for docs/studio.md (a studio must be serving a folder with
runs named after the studies, plus sphere-seed1..6 of ``functions`` for the comparison).

    python scripts/studio_screenshots.py BASE_URL TOKEN OUT_DIR
"""

from __future__ import annotations

import sys
from pathlib import Path

from playwright.sync_api import sync_playwright

PAGES = {"runs": "/", "run": "/run?name=grid-path", "step": "/run?name=humanoid-step",
         "kick": "/run?name=biped-kick", "repertoire": "/run?name=humanoid-repertoire",
         "arm-ik": "/run?name=arm-ik", "grid-path": "/run?name=grid-path",
         "quadruped": "/run?name=quadruped-plan",
         "compare": "/compare?runs=" + ",".join(f"sphere-seed{i}" for i in range(1, 7))}
ARGS = ["--no-sandbox", "--disable-gpu", "--disable-background-networking", "--no-first-run"]


def main() -> None:
    base, token, out = sys.argv[1], sys.argv[2], Path(sys.argv[3])
    out.mkdir(parents=True, exist_ok=True)
    with sync_playwright() as p:
        b = p.chromium.launch(executable_path="/usr/bin/chromium", args=ARGS)
        pg = b.new_page(viewport={"width": 1200, "height": 900})
        pg.goto(f"{base}/?token={token}")
        for name, path in PAGES.items():
            pg.goto(base + path)
            pg.wait_for_timeout(4000)
            if name in ("step", "kick", "repertoire", "arm-ik", "grid-path", "quadruped"):
                pg.locator(".study-view").screenshot(path=str(out / f"studio-{name}.png"))
            else:
                pg.screenshot(path=str(out / f"studio-{name}.png"), full_page=name != "run")
        pg.goto(f"{base}/new?study=functions")
        pg.wait_for_timeout(2000)
        pg.locator('input[data-key="algorithm.pop_size"], [data-key="algorithm.pop_size"] '
                   'input').first.fill("-4")
        pg.wait_for_timeout(1500)
        pg.screenshot(path=str(out / "studio-new.png"))
        b.close()


if __name__ == "__main__":
    main()
