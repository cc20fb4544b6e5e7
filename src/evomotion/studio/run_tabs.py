"""Two tabs of the run page (issue 35): **files** (the run's videos played in the page, its
plots shown, every file downloadable) and **metrics** (any column of ``stats.csv`` plotted,
log scale, smoothing, zoom, PNG and CSV export)."""

from __future__ import annotations

import math
from pathlib import Path
from urllib.parse import quote

from evomotion.studio import run_files as rf

MAX_VIDEOS = 6
MAX_IMAGES = 12
#: columns of stats.csv that are not metrics to plot against generations
NOT_METRICS = ("generation",)
DEFAULT_METRICS = ("best_so_far", "mean")
#: a tooltip's number: 6 significant digits, no trailing zeros, '-' when missing (NiceGUI
#: evaluates option keys starting with ':' as JavaScript)
VALUE_FORMATTER = ("v => (v == null || !isFinite(v)) ? '-' : "
                   "String(Number(Number(v).toPrecision(6)))")


def file_url(root: Path, run_dir: Path, rel: str, download: bool = False) -> str:
    path = f"{run_dir.relative_to(root).as_posix()}/{rel}"
    return f"/files?path={quote(path)}" + ("&download=1" if download else "")


def files_panel(ui, root: Path, run_dir: Path) -> None:
    """Videos, plots and a table of every file of the run with a download link."""
    files = rf.run_files(run_dir)
    if not files:
        ui.label("no files in this run yet").classes("files-empty")
        return
    videos = [f for f in files if f.kind == "video"][:MAX_VIDEOS]
    stems: set[str] = set()  # plots/fitness.png and .svg: the first one only
    images = []
    for f in files:
        stem = f.rel.rsplit(".", 1)[0]
        if f.kind == "image" and stem not in stems:
            stems.add(stem)
            images.append(f)
    images = images[:MAX_IMAGES]
    if videos:
        with ui.row().classes("w-full gap-4"):
            for f in videos:
                with ui.column().classes("gap-0"):
                    ui.label(f.rel).classes("font-mono text-sm")
                    ui.video(file_url(root, run_dir, f.rel), autoplay=False, muted=True) \
                        .classes("w-96 run-video").props(f"data-file={f.rel}")
    if images:
        with ui.row().classes("w-full gap-4"):
            for f in images:
                with ui.column().classes("gap-0"):
                    ui.label(f.rel).classes("font-mono text-sm")
                    ui.image(file_url(root, run_dir, f.rel)).classes("w-96 run-image") \
                        .props(f"data-file={f.rel} fit=contain")
    rows = [{"file": f.rel, "kind": f.kind, "size": rf.size_text(f.size),
             "url": file_url(root, run_dir, f.rel, download=True)} for f in files]
    table = ui.table(columns=[{"name": "file", "label": "file", "field": "file",
                               "align": "left", "sortable": True},
                              {"name": "kind", "label": "kind", "field": "kind",
                               "sortable": True},
                              {"name": "size", "label": "size", "field": "size"}],
                     rows=rows, row_key="file", pagination=25).classes("w-full run-files")
    table.add_slot("body-cell-file", r'''
        <q-td :props="props"><a :href="props.row.url" download class="text-blue-700 underline
           file-link">{{ props.row.file }}</a></q-td>''')
    if len(files) >= rf.MAX_FILES:
        ui.label(f"only the first {rf.MAX_FILES} files are listed").classes("text-slate-600")


def smooth(values: list[float | None], weight: float) -> list[float | None]:
    """TensorBoard's exponential moving average with debiasing (``weight`` in [0, 1));
    missing values stay missing and do not move the average."""
    if weight <= 0:
        return list(values)
    out: list[float | None] = []
    last, n = 0.0, 0
    for v in values:
        if v is None or not math.isfinite(v):
            out.append(None)
            continue
        last, n = last * weight + (1 - weight) * v, n + 1
        out.append(last / (1 - weight ** n))
    return out


#: points per curve sent to the browser at most (a run of 10,000 generations made a 1.8 s page)
MAX_POINTS = 2000


def decimate(x: list, y: list, max_points: int = MAX_POINTS) -> list[list]:
    """``[[x, y], ...]`` with at most about ``max_points`` points: past that, per bucket of
    consecutive rows the lowest and the highest point (in row order), so a curve keeps its
    envelope, spikes included; missing values (None) stay gaps."""
    n = min(len(x), len(y))
    if n <= max_points:
        return [[a, b] for a, b in zip(x[:n], y[:n], strict=True)]
    import numpy as np

    xs = np.array([np.nan if v is None else v for v in x[:n]], float)
    ys = np.array([np.nan if v is None else v for v in y[:n]], float)
    edges = np.linspace(0, n, max_points // 2 + 1).astype(int)
    keep = [0, n - 1]
    for lo, hi in zip(edges[:-1], edges[1:], strict=True):
        seg = ys[lo:hi]
        if hi > lo and np.isfinite(seg).any():
            keep += [lo + int(np.nanargmin(seg)), lo + int(np.nanargmax(seg))]
        elif hi > lo:
            keep.append(lo)  # a gap stays a gap
    idx = np.unique(keep)
    return [[None if not np.isfinite(xs[i]) else float(xs[i]),
             None if not np.isfinite(ys[i]) else float(ys[i])] for i in idx]


def metric_columns(columns: list[str]) -> list[str]:
    return [c for c in columns if c not in NOT_METRICS]


def metrics_panel(ui, st, csv_url: str):
    """The metrics chart over ``st`` (a :class:`~evomotion.studio.data.StatsTail`); returns its
    redraw function (called by the page when new rows arrive)."""
    with ui.row().classes("items-center gap-4"):
        pick = ui.select([], multiple=True, value=[], label="metrics") \
            .classes("min-w-96 metric-pick").props("use-chips")
        log_y = ui.checkbox("log y").classes("metric-log")
        ui.label("smoothing")
        weight = ui.slider(min=0.0, max=0.99, step=0.01, value=0.0).classes("w-48 metric-smooth")
        ui.link("stats.csv", csv_url).classes("metric-csv").props("download")
    chart = ui.echart({
        "animation": False, "legend": {"top": 0},
        "tooltip": {"trigger": "axis", ":valueFormatter": VALUE_FORMATTER},
        "toolbox": {"feature": {"saveAsImage": {"title": "PNG"}, "dataZoom": {}}},
        "dataZoom": [{"type": "inside"}, {"type": "slider", "height": 18, "bottom": 0}],
        "grid": {"left": 70, "right": 30, "top": 40, "bottom": 60},
        "xAxis": {"type": "value", "name": "generation", "nameLocation": "middle",
                  "nameGap": 25, "minInterval": 1},
        "yAxis": {"type": "value", "scale": True}, "series": []}) \
        .classes("w-full h-96 metrics-chart")

    def redraw() -> None:
        cols = metric_columns(st.columns)
        if list(pick.options) != cols:
            pick.set_options(cols, value=[c for c in (pick.value or []) if c in cols] or
                             [c for c in DEFAULT_METRICS if c in cols][:2])
        x = st.column("generation")
        series = []
        for name in pick.value or []:
            ys = smooth(st.column(name), float(weight.value or 0.0))
            if log_y.value:
                ys = [v if v is not None and v > 0 else None for v in ys]
            pts = decimate(x, ys)
            series.append({"name": name, "type": "line", "data": pts,
                           "showSymbol": sum(p[1] is not None for p in pts) <= 30})
        chart.options["series"] = series
        chart.options["yAxis"]["type"] = "log" if log_y.value else "value"
        chart.update()

    for w in (pick, log_y, weight):
        w.on_value_change(lambda _: redraw())
    return redraw
