"""The studio end to end, in headless Chromium: runs list, every study's run page, a live run
growing, stop and resume from the page, a run started from the form (identical to the CLI's),
the comparison, and the token."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import time
from pathlib import Path
from urllib.parse import quote

import pytest
from studio_helpers import TOKEN, get, smoke_sets

from evomotion.run.config import resolve_config
from evomotion.run.runner import run_study
from evomotion.run.stats import read_stats
from evomotion.studies import STUDIES, get_study

pytestmark = pytest.mark.slow

VIEW = {"arm-ik": ".view-image", "grid-path": ".view-image", "quadruped-plan": ".view-image",
        "humanoid-step": ".nao-scene", "humanoid-walk-open-loop": ".nao-scene",
        "biped-kick": ".kick-table", "humanoid-repertoire": ".repertoire-map",
        "functions": "text=no view of its own", "gym": "text=no view of its own",
        "humanoid-balance": ".played-caption:has-text('unseen world 0')",
        "humanoid-walk": ".drive-scene"}


def _rows(page) -> int:
    text = page.locator(".run-summary").inner_text()
    return int(text.rsplit(",", 1)[1].split()[0]) if "rows" in text else 0


def _field(page, key: str):
    return page.locator(f'input[data-key="{key}"], [data-key="{key}"] input').first


def _status(page) -> str:
    """The run page's status badge and action message (for a timeout's message)."""
    try:
        return (f"status {page.locator('.run-status').inner_text(timeout=2000)!r}, message "
                f"{page.locator('.action-message').inner_text(timeout=2000)!r}")
    except Exception as e:  # the page itself is gone: say so, keep the timeout's message
        return f"page unreadable: {type(e).__name__}"


def _run_state(out: Path) -> str:
    """A run folder's lock, its process's state and the tails of its log and stderr (for a
    timeout's message)."""
    from evomotion.run.lock import LOCK_NAME
    from evomotion.studio.actions import STDERR_NAME

    parts = []
    for name, n in ((LOCK_NAME, 300), ("log.txt", 300), (STDERR_NAME, 600)):
        try:
            parts.append(f"{name}: {(out / name).read_text(errors='replace')[-n:]!r}")
        except OSError as e:
            parts.append(f"{name}: {type(e).__name__}")
    try:
        pid = json.loads((out / LOCK_NAME).read_text())["pid"]
        status = Path(f"/proc/{pid}/status").read_text().splitlines()
        parts += [x for x in status if x.split(":")[0] in ("State", "SigPnd", "ShdPnd",
                                                            "SigBlk", "SigIgn", "SigCgt")]
        import shutil
        if shutil.which("py-spy"):  # where the process is (a debugging aid, not a dependency)
            parts.append(subprocess.run(["py-spy", "dump", "--pid", str(pid)],
                                        capture_output=True, text=True).stdout[-3000:])
    except (OSError, ValueError, KeyError, TypeError) as e:
        parts.append(f"process: {type(e).__name__}")
    return "; ".join(parts)


def _act(page, button: str, answer: str, done=lambda: False) -> None:
    """Click ``button`` until the page's action message says ``answer`` (the studio confirms
    each action: a click that a loaded browser lost, its socket reconnecting, is clicked
    again) or ``done()`` (the action's effect) shows: an action seen done is not repeated."""
    def said() -> bool:
        return answer in page.locator(".action-message").inner_text() or done()

    for _ in range(3):
        page.locator(button).click()
        try:
            _wait(said, 20, answer)
            return
        except AssertionError:
            if done():
                return
    raise AssertionError(f"{button}: no {answer!r} ({_status(page)})")


def _wait(cond, timeout=30.0, what="condition"):
    end = time.time() + timeout
    while time.time() < end:
        if cond():
            return
        time.sleep(0.25)
    raise AssertionError(f"timed out waiting for {what() if callable(what) else what}")


def test_every_study_has_a_view():
    assert set(VIEW) == set(STUDIES)


def test_runs_list_shows_every_run(page, studio):
    page.wait_for_selector(".runs-table tbody tr")
    _wait(lambda: page.locator(".runs-table tbody tr").count() == len(STUDIES), what="rows")
    text = page.locator(".runs-table").inner_text()
    for name in STUDIES:
        assert name in text
    assert "finished" in text
    page.locator(".runs-table tbody tr", has_text="grid-path").first.click()
    page.wait_for_url("**/run?name=grid-path")


@pytest.mark.parametrize("name", sorted(STUDIES))
def test_run_page_shows_curves_and_the_study_view(page, studio, name):
    base, root = studio
    page.goto(f"{base}/run?name={quote(name)}")
    page.wait_for_selector(".fitness-chart canvas")
    n = len(read_stats(root / name / "stats.csv")["generation"])
    _wait(lambda: _rows(page) == n, what=f"{n} rows")
    assert "finished" in page.locator(".run-status").inner_text()
    page.wait_for_selector(VIEW[name], timeout=30000)
    if VIEW[name] == ".view-image":  # a rendered figure, stepped back one generation
        src = page.locator(".view-image img").get_attribute("src")
        assert src and src.startswith("data:image/png")
    if name in STUDIES and get_study(name).view and get_study(name).view.motions:
        page.wait_for_selector(".nao-scene", timeout=60000)  # the kick's failed after its table
    assert page.locator(".view-error").count() == 0, page.locator(".view-error").inner_text()
    page.locator(".q-tab", has_text="config").click()
    page.wait_for_selector(".run-config", state="visible")  # its text arrives after it
    _wait(lambda: f'study = "{name}"' in page.locator(".run-config").inner_text(),
          what="the run's config")


def test_live_run_grows_then_stop_and_resume_from_the_page(page, studio):
    base, root = studio
    out = root / "live"
    sets = [*smoke_sets("humanoid-walk-open-loop"), "run.generations=400", "run.checkpoint_every=2"]
    args = [a for s in sets for a in ("--set", s)]
    proc = subprocess.Popen([sys.executable, "-m", "evomotion.cli", "run",
                             "humanoid-walk-open-loop", *args, "--out", str(out), "--quiet"])
    try:
        _wait(lambda: (out / "stats.csv").exists(), what="the run to start")
        page.goto(f"{base}/")  # the list shows it running (it refreshes itself)
        row = page.locator(".runs-table tbody tr", has_text="live").first
        _wait(lambda: row.count() and "running" in row.inner_text(), 30, "a running row")
        page.goto(f"{base}/run?name=live")
        page.wait_for_selector(".fitness-chart canvas")
        _wait(lambda: _rows(page) >= 2, what="first rows")
        first = _rows(page)
        _wait(lambda: _rows(page) >= first + 3, what="the curve to grow without a reload")
        assert "running" in page.locator(".run-status").inner_text()
        _act(page, ".stop-button", "stop sent to process", lambda: "running" not in
             page.locator(".run-status").inner_text())
        _wait(lambda: "interrupted" in page.locator(".run-status").inner_text(), 90,
              lambda: f"the stop ({_status(page)}; {_run_state(out)})")
        assert proc.wait(30) == 130
        assert "stopped: interrupted" in (out / "log.txt").read_text()
        stopped_at = _rows(page)
        _act(page, ".resume-button", "resume started in process",
             lambda: "running" in page.locator(".run-status").inner_text())
        _wait(lambda: "running" in page.locator(".run-status").inner_text(), 60, "resume")
        _wait(lambda: _rows(page) > stopped_at, 60, "the resumed run to go on")
        _act(page, ".stop-button", "stop sent to process", lambda: "running" not in
             page.locator(".run-status").inner_text())
        _wait(lambda: "interrupted" in page.locator(".run-status").inner_text(), 90,
              lambda: f"the second stop ({_status(page)}; {_run_state(out)})")
    finally:
        if proc.poll() is None:
            proc.kill()


def test_run_started_from_the_form_is_the_cli_run(page, studio, tmp_path):
    base, root = studio
    page.goto(f"{base}/new?study=functions")
    field = _field(page, "algorithm.pop_size")
    field.fill("-4")
    _field(page, "run.generations").fill("-1")
    # every error at once, each under its own field (issue 35: one at a time)
    page.wait_for_selector(".field-error:has-text('algorithm.pop_size')")
    page.wait_for_selector(".field-error:has-text('run.generations')")
    _wait(lambda: "2 errors" in page.locator(".form-error").inner_text(), what="the count")
    assert page.locator(".start-button").is_disabled()
    page.screenshot(path=str(tmp_path / "form-errors.png"), full_page=True)
    field.fill("12")
    _field(page, "run.generations").fill("7")
    _field(page, "run.seed").fill("4")
    _wait(lambda: "run.seed=4" in page.locator(".new-command").inner_text(), what="command")
    page.locator(".start-button").click()
    page.wait_for_url("**/run?name=functions-*")
    name = page.url.split("name=")[1]
    run_dir = root / name
    _wait(lambda: "finished" in page.locator(".run-status").inner_text(), 60, "the run")
    cli = tmp_path / "cli"
    subprocess.run([sys.executable, "-m", "evomotion.cli", "run", "functions", "--set",
                    "algorithm.pop_size=12", "--set", "run.generations=7", "--set",
                    "run.seed=4", "--out", str(cli), "--quiet"], check=True)
    a, b = read_stats(run_dir / "stats.csv"), read_stats(cli / "stats.csv")
    for col in a:
        if col not in ("wall_s", "evals_per_s"):
            assert a[col].tobytes() == b[col].tobytes(), col
    ja, jb = (json.loads((d / "best.json").read_text()) for d in (run_dir, cli))
    assert ja["genome"] == jb["genome"] and ja["fitness"] == jb["fitness"]
    assert (run_dir / "config.toml").read_text() == (cli / "config.toml").read_text()


def test_a_preset_that_is_another_study_opens_that_studys_form(page, studio):
    """`humanoid-walk --preset open-loop` runs the study humanoid-walk-open-loop: the form
    lists the preset and opens that study's own form (its fields follow the study)."""
    base, _ = studio
    page.goto(f"{base}/new?study=humanoid-walk")
    page.wait_for_selector(".new-command")
    _pick(page, page.locator(".new-preset"), "open-loop: the study humanoid-walk-open-loop",
          rebuilds=False, exact=False)  # it opens another page
    page.wait_for_url("**/new?study=humanoid-walk-open-loop")
    _wait(lambda: "run humanoid-walk-open-loop" in page.locator(".new-command").inner_text(),
          20, "the open-loop walk's form")


def _build(page) -> int:
    """How many times the new-run form built its fields (its ``data-build``)."""
    return int(page.locator(".new-fields").get_attribute("data-build") or 0)


def _pick(page, select, option: str, rebuilds: bool = True, exact: bool = True) -> None:
    """Picks ``option`` in the form's ``select``. A click during an animation under CI load
    opens no menu: it clicks again. With ``rebuilds``, waits for the rebuild of the fields that
    the pick causes to land, so the next click finds the new fields, not ones being replaced."""
    from playwright.sync_api import TimeoutError as PlaywrightTimeout

    n = _build(page) if rebuilds else 0
    item = page.get_by_role("option", name=option, exact=exact)
    for _ in range(3):
        select.click()
        try:
            item.wait_for(state="visible", timeout=10_000)
            break
        except PlaywrightTimeout:
            continue
    item.click()
    if rebuilds:
        _wait(lambda: _build(page) > n, 30, f"the form to rebuild for {option}")


def _chooser(page, key: str):
    """``choose(option, rebuilds=True)``: picks ``option`` in the select of ``key`` (under
    "advanced" the expansion is opened first)."""
    def choose(option: str, rebuilds: bool = True) -> None:
        select = page.locator(f'[data-key="{key}"]')
        if not select.is_visible():
            page.locator(".advanced-keys").first.click()
            select.wait_for(state="visible", timeout=10_000)
        _pick(page, select, option, rebuilds)
    return choose


def test_a_robot_with_defaults_of_its_own_shows_them_in_the_form(page, studio, tmp_path):
    """``humanoid-walk --robot dm-humanoid`` has defaults of its own (Study.robot_defaults):
    choosing the robot rebuilds the fields with them, the command names the robot only, and
    another robot brings the study's defaults back."""
    base, _ = studio
    page.goto(f"{base}/new?study=humanoid-walk")
    page.wait_for_selector(".new-command")
    assert _field(page, "problem.vx_min").input_value() == "-0.2"
    choose = _chooser(page, "problem.robot")
    choose("dm-humanoid")
    _wait(lambda: _field(page, "problem.vx_min").input_value() == "0.15", 20,
          "the dm humanoid's defaults")
    assert _field(page, "problem.sway_m").input_value() == "0.008"
    _wait(lambda: "dm-humanoid" in page.locator(".new-command").inner_text(), 10, "command")
    command = page.locator(".new-command").inner_text()
    assert "sway_m" not in command and "vx_min" not in command
    assert page.locator(".start-button").is_enabled()
    page.screenshot(path=str(tmp_path / "robot-defaults.png"), full_page=True)
    choose("op3")
    _wait(lambda: _field(page, "problem.vx_min").input_value() == "-0.2", 20,
          "the study's defaults")
    assert _field(page, "problem.sway_m").input_value() == "0.025"
    _wait(lambda: "op3" in page.locator(".new-command").inner_text(), 10, "command")
    assert "dm-humanoid" not in page.locator(".new-command").inner_text()


def test_gyms_environment_picks_its_own_defaults_and_method(page, studio, tmp_path):
    """gym's defaults are per environment (``Study.defaults_key = "env"``): Hopper-v5 runs
    CMA-ES, another task ARS; choosing the task in the form switches the method and its
    fields, and the command names the task only."""
    pytest.importorskip("gymnasium")
    base, _ = studio
    page.goto(f"{base}/new?study=gym")
    page.wait_for_selector(".new-command")
    assert "cmaes" in page.locator(".new-algorithm").inner_text()
    assert _field(page, "algorithm.sigma0").input_value() == "0.0005"
    choose = _chooser(page, "problem.env")
    choose("Walker2d-v5")
    _wait(lambda: "ars" in page.locator(".new-algorithm").inner_text(), 20, "ARS on Walker2d")
    _wait(lambda: _field(page, "algorithm.step_size").input_value() == "0.03", 20,
          "the paper's ARS of Walker2d")
    _wait(lambda: "Walker2d-v5" in page.locator(".new-command").inner_text(), 10, "command")
    assert "algorithm.name" not in page.locator(".new-command").inner_text()
    page.screenshot(path=str(tmp_path / "gym-env-defaults.png"), full_page=True)

    def preset(label: str) -> None:
        _pick(page, page.locator(".new-preset"), label, exact=False)

    preset("paper: ARS with")  # the paper's ARS of each task, then the defaults again
    _wait(lambda: "ars" in page.locator(".new-algorithm").inner_text(), 20, "the paper's ARS")
    assert _field(page, "algorithm.step_size").input_value() == "0.03"  # Walker2d's, not Hopper's
    choose("Swimmer-v5")  # the paper's Swimmer: V1-t, one direction, not normalised
    _wait(lambda: _field(page, "algorithm.pop_size").input_value() == "2", 20, "Swimmer's ARS")
    assert _field(page, "algorithm.step_size").input_value() == "0.02"
    choose("Walker2d-v5")
    _wait(lambda: _field(page, "algorithm.pop_size").input_value() == "80", 20, "Walker2d's")
    preset("default (best known)")
    _wait(lambda: _field(page, "algorithm.top_directions").input_value() == "30", 20,
          "Walker2d's defaults")
    assert "ars" in page.locator(".new-algorithm").inner_text()
    assert "algorithm.name" not in page.locator(".new-command").inner_text()
    choose("Hopper-v5")
    _wait(lambda: "cmaes" in page.locator(".new-algorithm").inner_text(), 20, "CMA-ES again")
    _wait(lambda: _field(page, "algorithm.sigma0").input_value() == "0.0005", 20, "its sigma")
    choose("Swimmer-v5", rebuilds=False)  # the same defaults as Hopper's: no rebuild, and
    _pick(page, page.locator(".new-algorithm"), "snes")  # kept through the next one
    _wait(lambda: "Swimmer-v5" in page.locator(".new-command").inner_text(), 20, "Swimmer kept")
    assert page.locator(".start-button").is_enabled()


def test_a_cloned_runs_robot_brings_its_defaults_and_the_runs_values_stay(page, studio):
    """A dm humanoid run cloned: the form shows the dm humanoid's defaults with the run's own
    values over them, so a value the run had that equals the NAO's default (sway 0.025 m) is
    still sent (it was dropped, and the clone ran the robot's 0.008)."""
    import shutil

    base, root = studio
    s = get_study("humanoid-walk")
    name = "dm-walk-clone-source"
    cfg = resolve_config(s, None, [*s.smoke, "run.generations=1", "run.videos=false",
                                   "problem.robot='dm-humanoid'", "problem.sway_m=0.025"])
    run_study(s, cfg, root / name, quiet=True)
    try:
        page.goto(f"{base}/new?study=humanoid-walk&clone={name}")
        page.wait_for_selector(".clone-note")
        _wait(lambda: "dm-humanoid" in page.locator(".new-command").inner_text(), 20,
              "the cloned robot")
        command = page.locator(".new-command").inner_text()
        assert "problem.sway_m=0.025" in command and "run.generations=1" in command
        assert _field(page, "problem.sway_phase_rad").input_value() == "1.57"  # dm's default
    finally:
        shutil.rmtree(root / name, ignore_errors=True)


def test_compare_page_draws_median_and_band(page, studio):
    base, root = studio
    page.goto(f"{base}/compare?runs=functions,grid-path")
    page.wait_for_selector(".compare-chart canvas")
    _wait(lambda: "2 runs of 2 studies" in page.locator(".compare-note").inner_text(),
          what="the note")
    assert "never pooled" in page.locator(".compare-note").inner_text()


def test_token_guards_pages_files_and_actions(studio):
    base, _ = studio
    assert get(f"{base}/")[0] == 403
    assert get(f"{base}/run?name=functions")[0] == 403
    assert get(f"{base}/files?path=functions/stats.csv")[0] == 403
    assert get(f"{base}/files?path=functions/stats.csv&token={TOKEN}")[0] == 200
    assert get(f"{base}/files?path=../../etc/passwd&token={TOKEN}")[0] == 404
    # actions need the header, not a cookie or a query a foreign page could send
    assert get(f"{base}/api/stop?name=functions&token={TOKEN}", method="POST")[0] == 403
    code, body = get(f"{base}/api/stop?name=functions", {"X-Evomotion-Token": TOKEN}, "POST")
    assert code == 400 and b"not running" in body
    code, body = get(f"{base}/api/runs", {"X-Evomotion-Token": TOKEN})
    assert code == 200 and len(json.loads(body)) >= len(STUDIES)


def test_studio_refuses_bad_arguments_in_one_line(tmp_path):
    env = dict(os.environ)
    for args, needle in ((["studio", str(tmp_path / "nope")], "no such folder"),
                         (["studio", str(tmp_path), "--port", "0"], "--port")):
        r = subprocess.run([sys.executable, "-m", "evomotion.cli", *args], env=env,
                           capture_output=True, text=True, timeout=60)
        assert r.returncode == 2 and needle in r.stderr and "Traceback" not in r.stderr
        assert len(r.stderr.strip().splitlines()) == 1


def _cell_xy(page, ix: int, iy: int, nx: int, ny: int) -> tuple[float, float]:
    page.locator(".repertoire-map").scroll_into_view_if_needed()  # the mouse needs it shown
    box = page.locator(".repertoire-map").bounding_box()  # grid margins of views._repertoire
    w, h = box["width"] - 180, box["height"] - 80
    return box["x"] + 90 + (ix + 0.5) * w / nx, box["y"] + 20 + (ny - 1 - iy + 0.5) * h / ny


def test_a_click_on_the_repertoire_map_plays_that_cell(page, studio):
    """Issue 35: the map counts what the CLI counts (it said "256 of 720 cells filled" where
    the CLI said "125 standing steps"), its tooltip names measures with units and the cell's
    state, a click plays a standing cell and says why a fallen one plays nothing."""
    import json

    from evomotion.run.archive_file import read_archive
    from evomotion.studio.archive_map import FELL, PLAYABLE, map_cells

    base, root = studio
    run = root / "humanoid-repertoire"
    a = read_archive(run / "archive.npz")
    index = json.loads((run / "repertoire" / "index.json").read_text())
    playable = {e["cell"] for e in index["entries"]}
    nx, ny = int(a.bins[0]), int(a.bins[1])
    page.goto(f"{base}/run?name=humanoid-repertoire")
    page.wait_for_selector(".repertoire-map canvas")
    page.wait_for_selector(".nao-scene")
    counts = page.locator(".repertoire-counts").inner_text()
    assert f"{len(index['entries'])} standing steps with a motion" in counts, counts
    assert f"{index['fallen']} fell" in counts and f"{index['outside_box']} standing outside" \
        in counts, counts
    shown = page.locator(".motion-pick").inner_text()
    cells = map_cells(a, playable, -9.0)
    fallen = [c for c in cells if c.state == FELL]
    if fallen:
        page.mouse.click(*_cell_xy(page, fallen[0].ix, fallen[0].iy, nx, ny))
        _wait(lambda: "fell" in page.locator(".repertoire-message").inner_text(), 10,
              "the message of a click on a fallen cell")
    others = [c for c in cells if c.state == PLAYABLE and f"cell-{c.cell:04d}" not in shown]
    if not others:
        pytest.skip("the smoke run has no second standing cell to click")
    target = others[0]
    page.mouse.move(*_cell_xy(page, target.ix, target.iy, nx, ny))
    _wait(lambda: f"cell {target.cell:04d}: dx" in page.inner_text("body"), 10, "the tooltip")
    assert target.tip in page.inner_text("body")
    page.screenshot(path=str(root / "repertoire-tooltip.png"))
    page.mouse.click(*_cell_xy(page, target.ix, target.iy, nx, ny))
    _wait(lambda: f"cell-{target.cell:04d}.motion" in page.locator(".motion-pick").inner_text(),
          20, "the clicked cell's motion")
    assert page.locator(".repertoire-message").inner_text() == ""


def test_the_study_view_updates_when_a_motion_appears(page, studio):
    """Issue 35: after a run wrote best.motion the open page still said "no .motion in this run
    yet" until a reload; the view now redraws when the run's artifacts change."""
    import shutil

    base, root = studio
    late = root / "late-motion"
    shutil.copytree(root / "humanoid-step", late, ignore=shutil.ignore_patterns("*.motion"))
    try:
        page.goto(f"{base}/run?name=late-motion")
        page.wait_for_selector(".fitness-chart canvas")
        _wait(lambda: "no .motion in this run yet" in page.locator(".study-view").inner_text(),
              what="the empty view")
        shutil.copy(root / "humanoid-step" / "best.motion", late / "best.motion")
        # (the generation player shows a scene already: wait for the motion's own player)
        _wait(lambda: "no .motion in this run yet" not in
              page.locator(".study-view").inner_text(), 30, "the redrawn view")
        assert "best.motion" in page.locator(".motion-pick").inner_text()
    finally:  # the other tests count the session's runs
        shutil.rmtree(late)


def test_files_tab_plays_videos_shows_plots_and_downloads_everything(page, studio):
    """Issue 35: a run's video plays in the page (Debian's Chromium decodes the H.264 the
    studies write), its plots show, and every file downloads under its own name."""
    import shutil

    import imageio.v2 as iio
    import numpy as np

    base, root = studio
    run = root / "with-video"
    shutil.copytree(root / "functions", run)
    writer = iio.get_writer(run / "best.mp4", fps=25, codec="libx264", pixelformat="yuv420p")
    for i in range(25):
        writer.append_data(np.full((64, 96, 3), i * 10, np.uint8))
    writer.close()
    try:
        page.goto(f"{base}/run?name=with-video")
        page.get_by_role("tab", name="files").click()
        page.wait_for_selector("video.run-video")
        _wait(lambda: page.evaluate("() => document.querySelector('video.run-video')"
                                    ".readyState") >= 1, 20, "the video's metadata")
        assert page.evaluate("() => document.querySelector('video.run-video').duration") \
            == pytest.approx(1.0, abs=0.1)
        page.wait_for_selector(".run-image img")
        links = page.locator(".run-files .file-link")
        names = [links.nth(i).inner_text() for i in range(links.count())]
        assert {"best.mp4", "config.toml", "best.json", "stats.csv"} <= set(names)
        with page.expect_download() as dl:
            links.nth(names.index("config.toml")).click()
        assert dl.value.suggested_filename == "config.toml"
        assert Path(dl.value.path()).read_bytes() == (run / "config.toml").read_bytes()
    finally:
        shutil.rmtree(run, ignore_errors=True)


def test_metrics_tab_plots_any_column_with_log_scale(page, studio):
    base, root = studio
    page.goto(f"{base}/run?name=functions")
    page.get_by_role("tab", name="metrics").click()
    page.wait_for_selector(".metrics-chart canvas")
    _pick(page, page.locator(".metric-pick"), "evals_per_s", rebuilds=False, exact=False)
    page.keyboard.press("Escape")
    _wait(lambda: "evals_per_s" in page.locator(".metric-pick").inner_text(), 10, "the pick")
    page.locator(".metric-log").click()
    page.wait_for_timeout(500)
    page.screenshot(path=str(root / "metrics.png"))


def test_compare_groups_by_a_config_key_shows_the_diff_and_writes_the_url(page, studio):
    """Issue 35: runs grouped by any config key (within a study), a config-diff table, and the
    selection written back to the URL."""
    import shutil

    base, root = studio
    other = root / "functions-seed7"
    shutil.copytree(root / "functions", other)
    cfg = other / "config.toml"
    cfg.write_text(cfg.read_text().replace("seed = 0", "seed = 7", 1))
    try:
        page.goto(f"{base}/compare?runs=functions,functions-seed7&by=run.seed")
        page.wait_for_selector(".compare-chart canvas")
        _wait(lambda: "2 groups" in page.locator(".compare-note").inner_text(), 20,
              "two groups by seed")
        _wait(lambda: "run.seed" in page.locator(".compare-diff").inner_text(), 20,
              "the diff table")
        assert "7" in page.locator(".compare-diff").inner_text()
        _pick(page, page.locator(".compare-by"), "study", rebuilds=False)
        _wait(lambda: "1 group:" in page.locator(".compare-note").inner_text(), 20,
              "one group by study")
        _wait(lambda: page.evaluate("location.search") ==
              "?runs=functions,functions-seed7", 20, "the URL")
        page.screenshot(path=str(root / "compare.png"), full_page=True)
    finally:
        shutil.rmtree(other, ignore_errors=True)


def test_clone_a_run_name_it_and_extend_it_from_the_page(page, studio):
    """Issue 35: the form starts from a run's config (clone), the new run gets the name typed,
    and a finished run is extended from its page (resume --set run.generations=N)."""
    import shutil

    base, root = studio
    page.goto(f"{base}/new?study=functions&clone=functions")
    page.wait_for_selector(".clone-note")
    # the smoke run's settings are filled in where they differ from the defaults
    _wait(lambda: "run.generations=5" in page.locator(".new-command").inner_text(), 10,
          "the cloned generations")
    assert "run.videos=false" in page.locator(".new-command").inner_text()
    page.locator(".new-name input").fill("functions")  # taken
    page.wait_for_selector(".name-error:has-text('exists already')")
    assert page.locator(".start-button").is_disabled()
    page.locator(".new-name input").fill("my-clone")
    page.locator(".new-tags input").fill("cloned, bad/tag")
    page.wait_for_selector(".name-error:has-text('bad/tag')")
    assert page.locator(".start-button").is_disabled()
    page.locator(".new-tags input").fill("cloned, e2e")
    _wait(lambda: page.locator(".name-error").inner_text() == "", 10, "the name accepted")
    page.locator(".start-button").click()
    page.wait_for_url("**/run?name=my-clone")
    run = root / "my-clone"
    try:
        assert (run / "tags.txt").read_text() == "cloned\ne2e\n"
        _wait(lambda: "finished" in page.locator(".run-status").inner_text(), 60, "the run")
        # tags edited on the run page, then shown beside the name and filtered by in the list
        page.locator(".run-tags input").fill("cloned extended")
        page.locator(".tags-button").click()
        page.wait_for_selector(".run-tags-message:has-text('saved')")
        assert (run / "tags.txt").read_text() == "cloned\nextended\n"
        last = int(read_stats(run / "stats.csv")["generation"][-1])
        page.locator(".extend-to input").fill(str(last + 2))
        _act(page, ".extend-button", "extension started in process",
             lambda: int(read_stats(run / "stats.csv")["generation"][-1]) > last)
        _wait(lambda: int(read_stats(run / "stats.csv")["generation"][-1]) == last + 2, 60,
              lambda: f"the extended run ({page.locator('.action-message').inner_text()})")
        assert "resumed at generation" in (run / "log.txt").read_text()
        page.goto(f"{base}/?tag=extended")
        page.wait_for_selector(".runs-table .run-tag")
        _wait(lambda: page.locator(".runs-count").inner_text() == "1 run tagged extended",
              20, lambda: page.locator(".runs-count").inner_text())
        row = page.locator(".runs-table tbody tr").first.inner_text()
        assert "my-clone" in row and "cloned" in row and "extended" in row
        page.screenshot(path=str(root / "runs-tags.png"))
    finally:
        shutil.rmtree(run, ignore_errors=True)


def test_the_3d_player_plays_in_the_browser_pauses_steps_and_slows(page, studio):
    """Issue 35: the poses are animated in the browser (no message per frame; it played at
    about 14 frames/s, 0.9x real time), with pause, frame stepping and slow motion."""
    base, _ = studio
    page.goto(f"{base}/run?name=humanoid-step")
    page.wait_for_function("Object.values(window.evoPlayers || {}).length > 0", timeout=60000)
    probe = "() => { const p = Object.values(window.evoPlayers)[0]; return [p.t, p.applied] }"
    t0, n0 = page.evaluate(probe)

    def played() -> bool:  # it plays by itself (slowly under a loaded CI: a frame rate that
        t1, n1 = page.evaluate(probe)  # follows the machine's load, so no fixed second)
        return n1 - n0 >= 3 and t1 != t0

    _wait(played, 15, "the player to apply 3 frames by itself")
    # motion analysis: angles and support plotted, a cursor at the playing time on each
    page.wait_for_selector(".motion-angles canvas")
    page.wait_for_selector(".motion-support canvas")
    cursor = "() => [...document.querySelectorAll('.nao-cursor')].map(e => e.style.transform)"
    c0 = page.evaluate(cursor)
    assert len(c0) == 3
    _wait(lambda: page.evaluate(cursor) != c0, 10, "the cursors to follow the playback")
    page.locator(".nao-controls .nao-play").first.click()
    page.wait_for_timeout(100)
    paused = page.evaluate(probe)[0]
    page.wait_for_timeout(500)
    assert page.evaluate(probe)[0] == paused
    assert page.locator(".nao-controls .nao-play").first.inner_text().lower() == "play"
    page.locator(".nao-controls .nao-fwd").first.click()
    page.wait_for_timeout(100)
    dt = 0.04  # frames recorded at 25 per second
    last = round(page.evaluate("() => Object.values(window.evoPlayers)[0].duration") / dt)
    assert page.evaluate(probe)[0] == pytest.approx(min(round(paused / dt) + 1, last) * dt,
                                                    abs=1e-6)
    page.locator(".nao-controls .nao-speed").first.select_option("0.25")
    page.locator(".nao-controls .nao-play").first.click()
    a = page.evaluate("() => [Object.values(window.evoPlayers)[0].t, performance.now()]")
    page.wait_for_timeout(1200)
    b = page.evaluate("() => [Object.values(window.evoPlayers)[0].t, performance.now()]")
    duration = page.evaluate("() => Object.values(window.evoPlayers)[0].duration")
    rate = ((b[0] - a[0]) % duration) / ((b[1] - a[1]) / 1000)
    assert 0.1 < rate < 0.5  # a quarter of real time


def test_the_balance_policy_plays_in_a_chosen_world_and_push(page, studio):
    """A policy study's view: the exported policy in an unseen world, shown as the closed loop
    played it (no open-loop replay), with its analysis; another world and push on request."""
    base, root = studio
    page.goto(f"{base}/run?name=humanoid-balance")
    page.wait_for_selector(".played-caption:has-text('unseen world 0')")
    page.wait_for_selector(".nao-scene")
    page.wait_for_selector(".motion-support canvas")
    page.locator(".played-world input").fill("7")
    page.locator(".played-push").click()
    page.locator(".q-menu .q-item", has_text="5 N s").click()
    page.locator(".played-button").click()
    _wait(lambda: "unseen world 7: a 5.00 N s push" in
          page.locator(".played-caption").inner_text(), 30,
          lambda: page.locator(".played-caption").inner_text())
    _wait(lambda: len(page.evaluate("Object.keys(window.evoPlayers || {})")) >= 1, 30,
          "the player")


def test_two_motions_ghosted_in_one_scene(page, studio):
    """Issue 35: a second motion of the run played in the same scene, translucent, on the same
    clock (the kick's aimed motions: the +30 kick ghosted over the straight one)."""
    base, root = studio
    page.goto(f"{base}/run?name=biped-kick")
    page.wait_for_selector(".motion-ghost")
    players = "() => Object.values(window.evoPlayers || {}).map(p => p.tracks)"
    _wait(lambda: len(page.evaluate(players)) >= 1, 30, "the player")
    page.locator(".motion-ghost").first.click()
    options = page.locator(".q-menu .q-item")
    _wait(lambda: options.count() > 1, 10, "the ghost choices")
    assert options.first.inner_text() == "(none)"
    options.nth(options.count() - 1).click()  # the last motion in natural order
    _wait(lambda: 2 in page.evaluate(players), 30, "a player with two motions")
    assert "ghost" in page.locator(".nao-fell").first.inner_text()
    probe = "() => Object.values(window.evoPlayers).find(p => p.tracks == 2).applied"
    n0 = page.evaluate(probe)
    page.wait_for_timeout(600)
    assert page.evaluate(probe) > n0  # both move on the same clock
    page.screenshot(path=str(root / "ghost.png"), full_page=True)


@pytest.mark.parametrize("name", ["humanoid-step", "humanoid-walk-open-loop", "biped-kick",
                                  "humanoid-repertoire"])
def test_the_best_of_any_generation_is_replayed(page, studio, name):
    """Issue 35: a slider over the recorded generations (run.history_every) replays the best of
    generation g in 3D (the study declares how a genome becomes a motion)."""
    base, root = studio
    page.goto(f"{base}/run?name={name}")
    page.wait_for_selector(".generation-step")
    _wait(lambda: "generation 5: its best" in page.locator(".generation-caption").inner_text(),
          30, "the last generation's best")
    slider = page.locator(".generation-step")
    slider.scroll_into_view_if_needed()
    box = slider.bounding_box()
    page.mouse.click(box["x"] + 1, box["y"] + box["height"] / 2)  # its left end
    _wait(lambda: "generation 0: its best" in page.locator(".generation-caption").inner_text(),
          30, "generation 0")
    _wait(lambda: page.evaluate("Object.keys(window.evoPlayers || {}).length") >= 2, 30,
          "a second player (best.motion and the generation's best)")
    page.locator(".generation-ghost").click()  # the last generation's best beside it
    _wait(lambda: "ghost: generation 5's best" in
          page.locator(".generation-caption").inner_text(), 30, "the ghost's caption")
    _wait(lambda: 2 in page.evaluate("Object.values(window.evoPlayers).map(p => p.tracks)"),
          30, "the generation player with a ghost")


def test_drive_the_walk_controller_live_from_the_keyboard(page, studio):
    """Issue 35: a walk controller driven live: a held key or the on-screen joystick sets the
    command, the simulation runs in real time on the server, restart (R) starts it again. The
    run is the smoke run with the kick study's shipped walk controller (a smoke-trained one
    falls at once)."""
    import re
    import shutil
    from importlib.resources import files

    base, root = studio
    run = root / "drive-shipped"
    shutil.copytree(root / "humanoid-walk", run)
    for name in ("policy.json", "policy.npz"):
        (run / name).write_bytes(
            (files("evomotion.studies.biped_kick") / "default_walk" / name).read_bytes())
    try:
        page.goto(f"{base}/run?name=drive-shipped")
        page.wait_for_selector(".drive-scene")

        def status() -> str:
            return page.locator(".drive-status").inner_text()

        def number(label: str) -> float:
            m = re.search(label + r"\s+([-+\d.]+)", status())
            return float(m.group(1)) if m else float("nan")

        _wait(lambda: number("t") > 0.3, 20, "the simulation to run")
        page.locator("body").click(position={"x": 5, "y": 5})  # the page has the focus
        page.keyboard.down("w")
        _wait(lambda: "command +0.45" in status(), 10, lambda: f"the command ({status()})")
        _wait(lambda: number("x") > 0.2, 20, lambda: f"walking forward ({status()})")
        page.keyboard.up("w")
        assert "FELL" not in status()
        pressed = time.monotonic()  # before the key: the server's restart comes after it
        page.keyboard.press("r")
        _wait(lambda: 0 <= number("t") < 0.6 and abs(number("x")) < 0.05, 10, "the restart")
        page.wait_for_timeout(2000)
        # real time: never ahead of the wall clock since the restart, and not far behind it
        # (a loaded server lags, then catches up at most 4 ticks a tick); t is read first
        t = number("t")
        wall = time.monotonic() - pressed
        assert 0.4 * wall < t <= wall + 0.05, (t, wall)
        # the on-screen joystick pushed fully up: the forward command at its largest
        pad = page.locator(".drive-joystick")
        pad.scroll_into_view_if_needed()
        box = pad.bounding_box()
        cx, cy = box["x"] + box["width"] / 2, box["y"] + box["height"] / 2
        page.mouse.move(cx, cy)
        page.mouse.down()
        page.mouse.move(cx, cy - 60, steps=5)
        _wait(lambda: "command +0.45" in status(), 10,
              lambda: f"the joystick's forward command ({status()})")
        page.mouse.up()
        _wait(lambda: "command +0.00 +0.00 +0.00" in status(), 10,
              lambda: f"the stop on release ({status()})")
        assert "FELL" not in status()
    finally:
        shutil.rmtree(run, ignore_errors=True)
