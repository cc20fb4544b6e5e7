"""The individual, per study, on a run's page: what the study declares in its
:class:`~evomotion.studies.view.StudyView`, drawn by the studio's generic views.

- ``motions``: any ``.motion`` of the run played in 3D on the run's robot (:mod:`.nao3d`), in
  the study's ``scene`` (the kick's: with the ball);
- ``table``: a JSON list of rows in the run folder (the kick's aimed kicks);
- ``archive_map``: the repertoire's heat map, where a click plays that cell's motion;
- ``genome_motion``: the best of any recorded generation replayed (a second motion ghosted
  over it on request);
- ``played``: a policy's closed-loop episode in a chosen unseen world and push, shown as it
  happened;
- ``frames``: the study's own matplotlib figures stepped through (a generation's population,
  a plan's states), rendered on the server; the study reads the run's files through
  :class:`StudioRunFiles`, which keeps the studio's size limits.

The studio knows no study by name.
"""

from __future__ import annotations

import base64
import io
import re
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.studies.view import NothingYetError
from evomotion.studio.readers import (
    bounded_files,
    check_robot,
    natural_key,
    one_line,
    regular_size,
)

#: the largest files a view reads (the studio stays well below 1 GB for any run folder)
MAX_HISTORY_BYTES = 256 << 20
MAX_ARCHIVE_BYTES = 128 << 20
MAX_JSON_BYTES = 32 << 20  # a study's JSON document (a plan)
MAX_TABLE_BYTES = 4 << 20
MAX_MAP_BINS = 4096  # bins per measure drawn in the repertoire's heat map
NO_GHOST = "(none)"  # the ghost picker's "no second motion"


def _png(fig) -> str:
    import matplotlib.pyplot as plt

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=90)
    plt.close(fig)
    return "data:image/png;base64," + base64.b64encode(buf.getvalue()).decode()


def _problem(study: str, run_dir: Path) -> Any:
    from evomotion.run.config import config_from_dict, config_from_run_dir
    from evomotion.studies import get_study

    s = get_study(study)
    _, raw = config_from_run_dir(run_dir)
    return s.make_problem(config_from_dict(s, raw).problem)


def robot_of(run_dir: Path) -> str | None:
    """The run config's ``problem.robot`` (``""``: the study's own robot) if the studio may
    load it (:func:`check_robot`: else one :class:`InputError` line); None without a readable
    config."""
    from evomotion.run.config import config_from_run_dir, configured_robot

    try:
        _, raw = config_from_run_dir(run_dir)
    except Exception:  # noqa: BLE001 - no readable config
        return None
    return check_robot(configured_robot(raw))


def scene_of(run_dir: Path, default: str = "nao") -> str:
    """The 3D scene of a run's motions: ``default`` (the NAO's) for a robot whose motions are
    Webots ``.motion`` files (the capability ``webots_names``), else ``"robot:<spec>"`` (its
    config's ``problem.robot``). A robot the studio must not
    load (not a bundled name, nor a regular spec file of bounded size: ``/dev/zero``, a FIFO,
    a huge file) is one :class:`InputError` line, and nothing is loaded."""
    robot = robot_of(run_dir)
    if robot is None:  # no readable config: the NAO's scene
        return default
    from evomotion.sim.robots import capabilities_of

    # the NAO scene plays Webots motions of the NAO's joints; any other robot its own scene
    return default if "webots_names" in capabilities_of(robot) else f"robot:{robot}"


def motions_of(run_dir: Path) -> list[str]:
    """The run's ``.motion`` files, relative to the run folder (best first, then in natural
    order: signed numbers by value, so the kick's ``aim_-30`` ... ``aim_+30``)."""
    found = [p.relative_to(run_dir).as_posix() for p in bounded_files(run_dir, ".motion")]
    return sorted(found, key=lambda n: (n != "best.motion", natural_key(n)))


def render(study: str, root: Path, run_dir: Path) -> None:
    from nicegui import ui

    from evomotion.studies import get_study

    try:
        view = get_study(study).view  # an unknown study (a damaged config) is one line
        if view is None:
            ui.label("this study has no view of its own: its curves are above")
            return
        scene = view.scene.name if view.scene is not None else None  # a declared scene
        if view.table:
            _table(ui, run_dir / view.table, view.table_title)
        if view.archive_map:
            _repertoire(ui, run_dir, scene, view.archive_fallen_at)
        elif view.motions:
            _nao(ui, run_dir, motions_of(run_dir), scene=scene)
        if view.frames is not None:
            _frames(ui, view.frames, StudioRunFiles(study, run_dir))
        if view.genome_motion is not None:
            from evomotion.studio.replays import generations

            generations(ui, StudioRunFiles(study, run_dir), view, scene or scene_of(run_dir))
        if view.played is not None:
            from evomotion.studio.replays import played

            played(ui, run_dir, view.played, scene_of(run_dir))
        if view.drive:
            from evomotion.studio.drive import drive_panel

            drive_panel(ui, run_dir, robot_of(run_dir) or "nao")
    except NothingYetError as e:
        ui.label(one_line(e)).classes("view-empty")
    except InputError as e:  # a file of the run the studio refuses to read or load
        ui.label(f"error: {one_line(e)}").classes("text-red-700 view-error")
    except Exception as e:  # noqa: BLE001 - a view must not take the page down
        ui.label(f"the study view failed: {type(e).__name__}: {one_line(e)}") \
            .classes("text-red-700 view-error")


class StudioRunFiles:
    """A run folder as a study's ``frames`` reads it (:class:`~evomotion.studies.view.RunFiles`):
    every file checked and bounded by the studio's limits."""

    def __init__(self, study: str, run_dir: Path) -> None:
        self.study, self.run_dir = study, run_dir

    def history(self) -> list:
        from evomotion.run.history import NAME, read_history

        path = self.run_dir / NAME
        if not path.exists():
            raise NothingYetError("no population.bin in this run (set run.history_every = 1 "
                                  "to record the populations)")
        regular_size(path, "population history", MAX_HISTORY_BYTES)
        hist = read_history(path)
        if not hist:
            raise NothingYetError("no generation recorded yet")
        return hist

    def stats(self) -> dict[str, list]:
        from evomotion.studio.data import StatsTail

        st = StatsTail(self.run_dir / "stats.csv")
        st.update()
        return {c: st.column(c) for c in st.columns}

    def problem(self) -> Any:
        return _problem(self.study, self.run_dir)

    def json(self, name: str, what: str) -> Any:
        from evomotion.textio import read_json

        path = self.run_dir / name
        if not path.exists():
            raise NothingYetError(f"no {name} in this run yet")
        return read_json(path, what, MAX_JSON_BYTES)


def _frames(ui, frames_of: Any, files: StudioRunFiles) -> None:
    frames = frames_of(files)
    if frames.title:
        ui.label(frames.title).classes("font-bold")
    _stepper(ui, frames.count, lambda k: _figure_caption(frames.draw(k)), frames.label)


def _figure_caption(drawn: tuple[Any, str]) -> tuple[str, str]:
    fig, caption = drawn
    return _png(fig), caption


def _nao(ui, run_dir: Path, motions: list[str], scene: str | None = None,
         chosen: str | None = None) -> Any:
    from evomotion.studio.nao3d import NaoPlayer

    scene = scene or scene_of(run_dir)
    if not motions:
        ui.label("no .motion in this run yet (written at checkpoints and at the end)")
        return None
    with ui.row().classes("items-center"):
        pick = ui.select(motions, value=chosen or motions[0], label="motion") \
            .classes("w-96 motion-pick")
        ghost = ui.select([NO_GHOST, *motions], value=NO_GHOST,
                          label="ghost: a second motion in the same scene") \
            .classes("w-96 motion-ghost")
    box = ui.column().classes("w-full")

    def show() -> None:
        box.clear()
        with box:
            NaoPlayer(run_dir / pick.value, scene=scene,
                      ghost=None if ghost.value == NO_GHOST else run_dir / ghost.value)

    pick.on_value_change(lambda _: show())
    ghost.on_value_change(lambda _: show())
    show()
    return pick


def _table(ui, path: Path, title: str) -> None:
    from evomotion.textio import read_json

    if not path.exists():
        return
    rows = read_json(path, "table", MAX_TABLE_BYTES)
    if not (isinstance(rows, list) and all(isinstance(r, dict) for r in rows)):
        raise InputError(f"{path}: expected a list of rows (JSON objects)")
    cols = [{"name": str(k), "label": str(k), "field": str(k)} for k in rows[0]] \
        if rows else []
    for r in rows:
        for k, v in r.items():
            if isinstance(v, float):
                r[k] = float(f"{v:.4g}")
    if title:
        ui.label(title).classes("font-bold")
    ui.table(columns=cols, rows=rows).classes("w-full kick-table")


def _repertoire(ui, run_dir: Path, scene: str | None = None,
                fallen_at: float | None = None) -> None:
    from evomotion.run.archive_file import read_archive
    from evomotion.studio import archive_map as amap

    motions = motions_of(run_dir)
    path = run_dir / "archive.npz"
    if not path.exists():
        _nao(ui, run_dir, motions, scene=scene)
        return
    regular_size(path, "archive", MAX_ARCHIVE_BYTES)
    a = read_archive(path)
    if a.kind != "grid" or len(a.bins) < 2 or not all(0 < int(b) <= MAX_MAP_BINS
                                                         for b in a.bins):
        ui.label(f"{a.kind} archive: no heat map; its elites' motions:")
        _nao(ui, run_dir, motions, scene=scene)
        return
    playable = {int(m[len("repertoire/cell-"):-len(".motion")]) for m in motions
                if re.fullmatch(r"repertoire/cell-\d+\.motion", m)}
    nx, ny = int(a.bins[0]), int(a.bins[1])
    xs = np.linspace(a.lower[0], a.upper[0], nx + 1)
    ys = np.linspace(a.lower[1], a.upper[1], ny + 1)
    ui.label(amap.counts_text(a, playable, fallen_at)).classes("font-bold repertoire-counts")
    slices = {-1: f"best over {amap.axis_name(a.measure_names[2])}" if len(a.bins) > 2
              else "all"}
    if len(a.bins) > 2:
        zs = np.linspace(a.lower[2], a.upper[2], int(a.bins[2]) + 1)
        slices.update({k: f"{amap.axis_name(a.measure_names[2])} {zs[k]:.3g}..{zs[k + 1]:.3g}"
                       for k in range(int(a.bins[2]))})
    shown: dict = {"cells": amap.map_cells(a, playable, fallen_at)}

    def by_series() -> list[list]:
        cells = shown["cells"]
        return [[m for m in cells if m.state != amap.FELL], [m for m in cells
                                                             if m.state == amap.FELL]]

    def clicked(e) -> None:
        groups = by_series()
        s, i = getattr(e, "series_index", 0) or 0, getattr(e, "data_index", None)
        if i is None or not 0 <= s < len(groups) or not 0 <= i < len(groups[s]):
            return
        cell = groups[s][i]
        message.set_text(amap.click_message(cell))
        name = f"repertoire/cell-{cell.cell:04d}.motion"
        if cell.state == amap.PLAYABLE and shown.get("pick") is not None and name in motions:
            shown["pick"].set_value(name)

    def reslice(k: int) -> None:
        shown["cells"] = amap.map_cells(a, playable, fallen_at, None if k < 0 else k)
        chart.options["series"] = amap.series(shown["cells"])
        chart.update()

    if len(slices) > 1:
        ui.select(slices, value=-1, label="slice", on_change=lambda e: reslice(e.value)) \
            .classes("w-72 repertoire-slice")
    lo, hi = amap.colour_range(amap.map_cells(a, playable, fallen_at))
    chart = ui.echart({
        "animation": False,
        "tooltip": {"position": "top", "confine": True, ":formatter": "p => p.data.tip"},
        "grid": {"left": 90, "right": 90, "bottom": 60, "top": 20},
        "xAxis": {"type": "category", "name": amap.axis_name(a.measure_names[0]),
                  "nameLocation": "middle",
                  "nameGap": 35, "data": [f"{(xs[i] + xs[i + 1]) / 2:.3g}" for i in range(nx)]},
        "yAxis": {"type": "category", "name": amap.axis_name(a.measure_names[1]),
                  "nameLocation": "middle",
                  "nameGap": 60, "data": [f"{(ys[i] + ys[i + 1]) / 2:.3g}" for i in range(ny)]},
        "visualMap": {"min": lo, "max": hi, "calculable": True, "seriesIndex": 0,
                      "dimension": 2, "orient": "vertical", "right": 0, "top": "center",
                      "precision": 3, "text": ["objective", ""],
                      "inRange": {"color": ["#440154", "#3b528b", "#21918c", "#5ec962",
                                            "#fde725"]}},
        "series": amap.series(shown["cells"])},
        on_point_click=clicked).classes("w-full h-96 repertoire-map")
    message = ui.label("").classes("text-slate-700 repertoire-message")
    shown["pick"] = _nao(ui, run_dir, motions, scene=scene)


def _stepper(ui, n: int, draw, label: str = "generation") -> None:
    img = ui.image().classes("w-full max-w-3xl view-image")
    caption = ui.label().classes("text-slate-600 view-caption")

    def show(k: int) -> None:
        src, text = draw(int(k))
        img.set_source(src)
        caption.set_text(text)

    with ui.row().classes("items-center w-full max-w-3xl"):
        ui.button(icon="chevron_left", on_click=lambda: slider.set_value(max(0, slider.value - 1)))
        slider: Any = ui.slider(min=0, max=max(n - 1, 0), value=max(n - 1, 0),
                                on_change=lambda e: show(e.value)).classes("w-96 view-step")
        ui.button(icon="chevron_right",
                  on_click=lambda: slider.set_value(min(n - 1, slider.value + 1)))
        ui.label(label)
    show(slider.value)
