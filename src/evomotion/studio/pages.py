"""The studio's pages: the runs list, one run (live curves, config, log, stop/resume and the
study's own view) and the comparison of runs; the new-run form is in :mod:`.form`."""

from __future__ import annotations

import json
import time
from pathlib import Path
from typing import Any
from urllib.parse import quote

from evomotion.errors import InputError
from evomotion.studio import actions, data, run_files, run_tabs, tags
from evomotion.studio.run_files import duration_text

STATUS_COLOURS = {"running": "blue", "finished": "green", "interrupted": "orange",
                  "failed": "red", "stale": "deep-orange", "remote": "purple",
                  "unverified": "grey", "unreadable": "red-10"}
CURVES = (("best_so_far", "best so far"), ("best", "best of generation"), ("mean", "mean"),
          ("min", "min"))


def _run_url(name: str) -> str:
    return f"/run?name={quote(name)}"


def _fmt_row(r: data.RunSummary) -> dict:
    d = r.row()
    d["status_text"] = r.status + (f" ({r.stop_reason})" if r.stop_reason else "") \
        + (", resumable" if r.resumable else "")
    d["best_text"] = "" if d["best"] is None else f"{d['best']:.6g}"
    try:
        d["started_text"] = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(r.started)) \
            if r.started > 0 else ""
    except (OverflowError, OSError, ValueError):  # a date no calendar holds
        d["started_text"] = ""
    d["duration_text"] = duration_text(r.duration_s)
    return d


#: the curves' tooltip: values to 6 significant digits (they printed 16), no trailing zeros;
#: the axis value (generation, evaluations) as a whole number (it read "84.00"); NiceGUI
#: evaluates keys starting with ':' as JavaScript
TOOLTIP = {"trigger": "axis", ":valueFormatter": run_tabs.VALUE_FORMATTER,
           "axisPointer": {"label": {":formatter": "p => String(Math.round(p.value))"}}}
#: a series with at most this many finite points shows its points as symbols
FEW_POINTS = 30


#: colours of the compared studies (ECharts' default palette)
PALETTE = ("#5470c6", "#91cc75", "#fac858", "#ee6666", "#73c0de", "#3ba272", "#fc8452",
           "#9a60b4")


def compare_series(groups: list[dict]) -> tuple[list[dict], list[str]]:
    """ECharts series and legend names of :func:`data.compare_groups`: per study a band (an
    invisible lower edge, left out of the legend, and the band stacked on it), its median and a
    thin line per run, all in the study's colour."""
    series: list[dict] = []
    legend: list[str] = []
    for k, g in enumerate(groups):
        colour = PALETTE[k % len(PALETTE)]
        x = g["evaluations"]
        band = [u - lo for u, lo in zip(g["q75"], g["q25"], strict=True)]
        stack = f"iqr-{k}"
        median = f"{g['study']}: median of {len(g['names'])}"
        series += [
            {"name": f"{g['study']} lower", "type": "line", "stack": stack, "showSymbol": False,
             "lineStyle": {"opacity": 0}, "data": [list(p) for p in zip(x, g["q25"])],
             "tooltip": {"show": False}},
            {"name": f"{g['study']}: interquartile band", "type": "line", "stack": stack,
             "showSymbol": False, "lineStyle": {"opacity": 0}, "color": colour,
             "areaStyle": {"color": colour, "opacity": 0.25},
             "data": [list(p) for p in zip(x, band)], "tooltip": {"show": False}},
            {"name": median, "type": "line", "showSymbol": len(x) <= FEW_POINTS,
             "color": colour, "lineStyle": {"width": 2.5},
             "data": [list(p) for p in zip(x, g["median"])]}]
        legend += [f"{g['study']}: interquartile band", median]
        for c in g["curves"]:
            series.append({"name": c["run"], "type": "line", "color": colour,
                           "showSymbol": len(c["evaluations"]) <= FEW_POINTS,
                           "lineStyle": {"width": 1, "opacity": 0.5},
                           "data": [list(p) for p in zip(c["evaluations"], c["best"])]})
            legend.append(c["run"])
    return series, legend


def header(ui, title: str) -> None:
    with ui.header().classes("items-center bg-slate-800"):
        ui.link("evomotion studio", "/").classes("text-white text-lg font-bold no-underline")
        ui.label(title).classes("text-slate-300")
        ui.space()
        ui.link("runs", "/").classes("text-white")
        ui.link("compare", "/compare").classes("text-white")
        ui.link("new run", "/new").classes("text-white")


def build(root: Path) -> None:
    from nicegui import ui

    from evomotion.studies import STUDIES
    from evomotion.studio import form, views

    @ui.page("/")
    def runs_page(study: str = "", tag: str = "") -> None:
        header(ui, "runs")
        if study not in STUDIES:
            study = ""
        cols = [{"name": k, "label": lab, "field": f, "sortable": True, "align": "left"}
                for k, lab, f in (("name", "run", "name"), ("study", "study", "study"),
                                  ("status", "status", "status_text"),
                                  ("generation", "generation", "generation"),
                                  ("evaluations", "evaluations", "evaluations"),
                                  ("best", "best", "best_text"),
                                  ("started", "started", "started_text"),
                                  ("duration", "duration", "duration_text"))]
        with ui.row().classes("items-center w-full"):
            pick = ui.select({"": "all studies", **{s: s for s in STUDIES}}, value=study,
                             label="study").classes("w-56 study-filter")
            tag_pick = ui.select({"": "all tags"}, value="", label="tag") \
                .classes("w-56 tag-filter")
            count = ui.label().classes("text-slate-500 runs-count")
        table = ui.table(columns=cols, rows=[], row_key="name",
                         pagination={"rowsPerPage": 50, "sortBy": "started",
                                     "descending": True}).classes("w-full runs-table")
        table.add_slot("body-cell-status", """
            <q-td :props="props"><q-badge :color="COLOURS[props.row.status]">
            {{ props.value }}</q-badge></q-td>""".replace("COLOURS", json.dumps(STATUS_COLOURS)
                                                          .replace('"', "'")))
        table.add_slot("body-cell-name", """
            <q-td :props="props">{{ props.value }}
            <q-badge v-for="t in props.row.tags" :key="t" color="blue-grey-2"
             text-color="blue-grey-10" class="q-ml-xs run-tag">{{ t }}</q-badge></q-td>""")
        table.on("rowClick", lambda e: ui.navigate.to(_run_url(e.args[1]["name"])))
        last: list = []
        every: list = []  # all rows of the study filter, before the tag filter

        def show(rows: list) -> None:
            every[:] = rows
            tags = sorted({t for r in rows for t in r["tags"]})
            wanted = tag_pick.value if tag_pick.value in tags else ""
            options = {"": "all tags", **{t: t for t in tags}}
            if options != tag_pick.options:
                tag_pick.set_options(options, value=wanted)
            shown = [r for r in rows if not wanted or wanted in r["tags"]]
            if shown != last:
                last[:] = shown
                table.rows = shown
                table.update()
                n = len(shown)
                count.set_text(f"{n} run{'s' * (n != 1)}" + (f" tagged {wanted}" if wanted else ""))

        def rows_now() -> list:
            return [_fmt_row(r) for r in data.list_runs(root, pick.value or None)]

        if tag:
            tag_pick.set_options({"": "all tags", tag: tag}, value=tag)
        tag_pick.on_value_change(lambda _: show(list(every)))

        busy = {"on": False}

        async def refresh() -> None:
            """Every 2 s, off the event loop: 1,000 run folders take about 0.3 s to read,
            which blocked every other page of the studio meanwhile."""
            from nicegui import run

            if busy["on"]:
                return
            busy["on"] = True
            try:
                rows = await run.io_bound(rows_now)
                if rows is not None:  # None: cancelled, or the studio is stopping
                    show(rows)
            finally:
                busy["on"] = False

        pick.on_value_change(lambda _: show(rows_now()))
        show(rows_now())
        ui.timer(2.0, refresh)

    @ui.page("/run")
    def run_page(name: str = "") -> None:
        header(ui, name)
        try:
            run_dir = data.resolve_run(root, name)
        except InputError as e:
            ui.context.client.status_code = 404
            ui.label(f"error: {e}").classes("text-red-700 run-error")
            return
        study = data.study_name(run_dir)
        with ui.row().classes("items-center"):
            ui.label(study).classes("text-xl font-bold")
            badge = ui.badge("").classes("run-status")
            stop_b = ui.button("stop", icon="stop").classes("stop-button")
            resume_b = ui.button("resume", icon="play_arrow").classes("resume-button")
            more = ui.number("extend to generations", value=None, min=1, precision=0) \
                .classes("w-48 extend-to")
            extend_b = ui.button("extend", icon="fast_forward").classes("extend-button")
            ui.link("clone", f"/new?study={quote(study)}&clone={quote(name)}") \
                .classes("clone-link")
            msg = ui.label().classes("text-red-700 action-message")
        tags.editor(ui, run_dir)
        with ui.row().classes("items-center"):
            xaxis = ui.toggle({"generation": "generation", "evaluations": "evaluations"},
                              value="generation").classes("x-axis")
            summary = ui.label().classes("text-slate-600 run-summary")
        chart = ui.echart({
            "animation": False, "tooltip": TOOLTIP, "legend": {"top": 0},
            "grid": {"left": 70, "right": 20, "top": 40, "bottom": 40},
            "xAxis": {"type": "value", "name": "generation", "nameLocation": "middle",
                      "nameGap": 25, "minInterval": 1},
            "yAxis": {"type": "value", "scale": True, "name": "fitness"},
            "series": [{"name": lab, "type": "line", "showSymbol": False, "data": []}
                       for _k, lab in CURVES]}).classes("w-full h-80 fitness-chart")
        st = data.StatsTail(run_dir / "stats.csv")

        def redraw() -> None:
            x = st.column(xaxis.value)
            for i, (k, _lab) in enumerate(CURVES):
                pts = run_tabs.decimate(x, st.column(k))
                chart.options["series"][i]["data"] = pts
                # a curve of few finite points (best_so_far inf, then one value) drew nothing
                chart.options["series"][i]["showSymbol"] = \
                    sum(p[1] is not None for p in pts) <= FEW_POINTS
            chart.options["xAxis"]["name"] = xaxis.value  # both axes count: whole ticks
            chart.update()

        def status() -> None:
            s, reason, pid = data.run_status(run_dir)
            seen["status"] = s
            badge.set_text(s + (f": {reason}" if reason else ""))
            badge.props(f"color={STATUS_COLOURS.get(s, 'grey')}")
            stop_b.set_enabled(s == "running")
            resume_b.set_enabled(data.is_resumable(run_dir, s))
            can_extend = s == "finished" or data.is_resumable(run_dir, s)
            extend_b.set_enabled(can_extend)
            more.set_enabled(can_extend)

        seen: dict[str, Any] = {"signature": data.artifact_signature(run_dir), "ticks": 0}

        def refresh_view() -> None:
            """Redraw the study view when the run's artifacts changed (every 2 s)."""
            seen["ticks"] += 1
            if seen["ticks"] % 2:
                return
            now = data.artifact_signature(run_dir)
            if now != seen["signature"]:
                seen["signature"] = now
                view_box.clear()
                with view_box:
                    views.render(study, root, run_dir)
                files_box.clear()
                with files_box:
                    run_tabs.files_panel(ui, root, run_dir)

        def tick() -> None:
            refresh_view()
            new = st.update()
            status()  # first: the summary's time left is only for a running run
            if new:
                redraw()
                metrics_redraw()
                show_log()
            if new or seen["status"] != seen.get("summarised"):
                seen["summarised"] = seen["status"]
                summary.set_text(run_files.progress(
                    cfg, st.last("generation"), st.last("evaluations"), st.last("wall_s"),
                    st.last("evals_per_s"), seen["status"] == "running") +
                    f", {len(st.rows)} rows")

        def act(fn, done: str) -> None:
            """Run the action; its confirmation (``done`` with the process id) or its one-line
            error under the buttons: a click always answers."""
            try:
                got = fn(root, name)
                pid = got if isinstance(got, int) else getattr(got, "pid", "?")
                msg.classes(replace="text-slate-700 action-message")
                msg.set_text(done.format(pid=pid))
            except InputError as e:
                msg.classes(replace="text-red-700 action-message")
                msg.set_text(str(e))
            status()

        stop_b.on_click(lambda: act(actions.stop_run, "stop sent to process {pid}: it "
                                    "checkpoints and ends"))
        resume_b.on_click(lambda: act(actions.resume_run, "resume started in process {pid}"))
        extend_b.on_click(lambda: act(lambda r, n: actions.extend_run(
            r, n, int(more.value) if isinstance(more.value, int | float) else -1),
            "extension started in process {pid}"))
        xaxis.on_value_change(lambda _: redraw())
        with ui.tabs().classes("w-full") as tabs:
            t_view = ui.tab("study view")
            t_metrics = ui.tab("metrics")
            t_files = ui.tab("files")
            t_cfg = ui.tab("config")
            t_log = ui.tab("log")
        with ui.tab_panels(tabs, value=t_view).classes("w-full"):
            with ui.tab_panel(t_view).classes("study-view"):
                view_box = ui.column().classes("w-full")
                with view_box:
                    views.render(study, root, run_dir)
            with ui.tab_panel(t_metrics):
                metrics_redraw = run_tabs.metrics_panel(
                    ui, st, run_tabs.file_url(root, run_dir, "stats.csv", download=True))
            with ui.tab_panel(t_files):
                files_box = ui.column().classes("w-full")
                with files_box:
                    run_tabs.files_panel(ui, root, run_dir)
            with ui.tab_panel(t_cfg):
                ui.code(data.read_config(run_dir)[0], language="toml").classes("w-full run-config")
            with ui.tab_panel(t_log):
                log = ui.code("", language="text").classes("w-full run-log")
                err_label = ui.label("").classes("font-bold mt-2 stderr-title")
                err = ui.code("", language="text").classes("w-full run-stderr")

        def show_log() -> None:
            log.set_content("\n".join(data.log_tail(run_dir, 60)))
            name, lines = run_files.stderr_tail(run_dir, 40)
            n = len(lines)
            err_label.set_text(f"stderr ({name}, last {n} line{'s' * (n != 1)})" if name else
                               "stderr: not recorded (a run started in a terminal printed it "
                               "there)")
            err.set_content("\n".join(lines))
            err.set_visibility(bool(name))

        cfg = data.read_config(run_dir)[1]
        show_log()
        tick()
        ui.timer(1.0, tick)

    @ui.page("/compare")
    def compare_page(runs: str = "", by: str = "study") -> None:
        from evomotion.studio import compare

        header(ui, "compare")
        names = [r.name for r in data.list_runs(root)]
        chosen = [n for n in runs.split(",") if n in names]
        with ui.row().classes("w-full items-end"):
            pick = ui.select(names, value=chosen, multiple=True, label="runs",
                             with_input=True).classes("grow compare-pick")
            group = ui.select(list(compare.ALWAYS), value="study", label="group by") \
                .classes("w-64 compare-by")
        note = ui.label().classes("text-slate-600 compare-note")
        chart = ui.echart({
            "animation": False, "tooltip": TOOLTIP, "legend": {"top": 0, "data": []},
            "xAxis": {"type": "value", "name": "evaluations", "nameLocation": "middle",
                      "nameGap": 25, "minInterval": 1},
            "yAxis": {"type": "value", "scale": True, "name": "best so far"},
            "series": []}).classes("w-full h-96 compare-chart")
        ui.label("where the selected runs' configs differ").classes("font-bold mt-2")
        diff = ui.table(columns=[], rows=[], row_key="key").classes("w-full compare-diff")

        def redraw() -> None:
            names = list(pick.value or [])
            dirs = [root / n for n in names]
            flat = dict(zip(dirs, compare.configs(dirs), strict=True))
            choices = compare.group_choices(list(flat.values()))
            if by_key["value"] not in choices:
                choices.append(by_key["value"])
            group.set_options(choices, value=by_key["value"])
            groups = data.compare_groups(dirs, labels=names, group_of=lambda d: compare
                                         .group_label(flat[d], by_key["value"]))
            series, legend = compare_series(groups)
            chart.options["series"], chart.options["legend"]["data"] = series, legend
            chart.update()
            cols, rows = compare.diff_table(names, list(flat.values()))
            diff.columns, diff.rows = cols, rows
            diff.update()
            studies = len({c.get("study") for c in flat.values()})
            note.set_text(
                f"{len(names)} runs of {studies} stud{'ies' if studies != 1 else 'y'} in "
                f"{len(groups)} group{'s' * (len(groups) != 1)}: one median and interquartile "
                "band per group of the best fitness so far, a thin line per run" +
                ("; runs of different studies are never pooled (their fitnesses are not "
                 "comparable)" if studies > 1 else ""))
            url = compare.page_url(names, by_key["value"])  # the selection is shareable
            ui.run_javascript(f"history.replaceState(null, '', {json.dumps(url)})")

        by_key = {"value": by or "study"}

        def regroup(value: str) -> None:
            if value and value != by_key["value"]:
                by_key["value"] = value
                redraw()

        pick.on_value_change(lambda _: redraw())
        group.on_value_change(lambda e: regroup(e.value))
        redraw()

    form.build(root)
