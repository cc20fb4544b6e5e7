"""The new-run page: a form generated from the study's config schema and presets.

Every field is one ``--set`` key; values are checked as the user types by the same resolver as
the CLI (:func:`evomotion.run.config.resolve_config`), and its one-line message is shown under
the field it names. The run starts as ``evomotion run ...`` in its own process
(:func:`evomotion.studio.actions.start_run`) and opens in its run page.
"""

from __future__ import annotations

from pathlib import Path
from urllib.parse import quote

from evomotion.errors import InputError
from evomotion.studio import actions, form_schema
from evomotion.studio.tags import parse_tags


def build(root: Path) -> None:
    from nicegui import ui

    from evomotion.run.config import default_algorithm, defaults_entry, study_algorithms
    from evomotion.studies import STUDIES, get_study
    from evomotion.studio.pages import header

    @ui.page("/new")
    def new_page(study: str = "", clone: str = "") -> None:
        header(ui, "new run")
        cloned, note = _cloned(root, clone) if clone else ({}, "")
        study = cloned.get("study", study) if isinstance(cloned.get("study"), str) else study
        if study not in STUDIES:
            study = next(iter(STUDIES))  # the registry's first (the quickest to try)
        s = get_study(study)
        with ui.row().classes("items-end"):
            pick = ui.select(list(STUDIES), value=study, label="study").classes("w-56 new-study")
            presets = {"": "default (best known)", **{p: f"{p}: {s.preset_notes.get(p, '')}"
                                                      for p in s.presets},
                       # a preset that is another study opens that study's form
                       **{p: f"{p}: the study {t} (its own form)"
                          for p, t in s.preset_studies.items()}}
            preset0 = cloned.get("preset") if cloned.get("preset") in s.presets else ""
            preset = ui.select(presets, value=preset0, label="preset") \
                .classes("w-96 new-preset")
            algs = list(study_algorithms(s))
            alg0 = (cloned.get("algorithm") or {}).get("name") \
                if isinstance(cloned.get("algorithm"), dict) else None
            problem0 = cloned.get("problem")
            robot0 = problem0.get(s.defaults_key) if isinstance(problem0, dict) else None
            alg = ui.select(algs, value=alg0 if alg0 in algs else
                            default_algorithm(s, robot0 if isinstance(robot0, str) else ""),
                            label="algorithm.name").classes("w-56 new-algorithm")
            run_name = ui.input("run name (optional)", placeholder=f"{study}-YYYYmmdd-HHMMSS") \
                .classes("w-72 new-name")
            run_tags = ui.input("tags (optional)", placeholder="baseline, lr-sweep") \
                .classes("w-72 new-tags")
        if note:
            ui.label(note).classes("text-slate-700 clone-note")
        pick.on_value_change(lambda e: ui.navigate.to(f"/new?study={quote(e.value)}"))
        name_error = ui.label().classes("text-red-700 text-xs name-error")
        run_name.on_value_change(lambda _: check())
        run_tags.on_value_change(lambda _: check())
        fields_box = ui.column().classes("w-full new-fields")
        error_top = ui.label().classes("text-red-700 form-error")
        command = ui.code("", language="bash").classes("w-full new-command")
        start = ui.button("start run", icon="rocket_launch").classes("start-button")
        state: dict = {"fields": [], "inputs": {}, "errors": {}, "clone_values": {}}

        def current_sets() -> list[str]:
            values = {k: (("true" if w.value else "false") if isinstance(w.value, bool)
                          else str(w.value)) for k, w in state["inputs"].items()}
            a = alg.value if alg.value != state["alg0"] else None
            sets = actions.changed_sets(state["fields"], values, a)
            # the robot's defaults are what the fields show: it is always sent
            if not any(x.startswith(f"problem.{s.defaults_key}=") for x in sets):
                sets += actions.robot_sets(study, state.get("robot"))
            return sets

        def check() -> bool:
            for lab in state["errors"].values():
                lab.set_text("")
            error_top.set_text("")
            sets = current_sets()
            p = preset.value or None
            name = (run_name.value or "").strip()
            try:
                if name:
                    actions.check_run_name(root, name)
                parse_tags(run_tags.value or "")
                name_error.set_text("")
            except InputError as e:
                name_error.set_text(f"error: {e}")
            command.set_content("evomotion " + " ".join(
                _quote(a) for a in actions.run_command(study, p, sets, Path("RUN_DIR"))))
            errors = actions.form_errors(study, p, sets, list(state["errors"]))
            for key, text in errors.items():  # every error at once, each under its field
                (state["errors"].get(key) or error_top).set_text(f"error: {text}")
            if len(errors) > 1:
                error_top.set_text(f"{len(errors)} errors: see the fields marked below" +
                                   (f"; error: {errors[None]}" if None in errors else ""))
            ok = not errors and not name_error.text
            start.set_enabled(ok)
            return ok

        def rebuild() -> None:
            fields_box.clear()
            state["builds"] = state.get("builds", 0) + 1  # the page's data-build: a test (or
            fields_box.props(f'data-build={state["builds"]}')  # a script) sees a rebuild land
            p = preset.value or None
            state["alg0"] = method_of(p)
            a = alg.value if alg.value != state["alg0"] else None
            try:
                state["fields"] = actions.form_fields(study, p, a, state.get("robot"))
            except InputError as e:
                error_top.set_text(f"error: {e}")
                return
            state["inputs"], state["errors"] = {}, {}
            state["clone_values"] = {}
            for f in state["fields"]:  # a cloned run's values where they differ
                sec, key = f.key.split(".", 1)
                got = cloned.get(sec)
                table = got if isinstance(got, dict) else {}
                if key in table:
                    text = form_schema.shown_text(f.kind, table[key])
                    if text != f.shown:
                        state["clone_values"][f.key] = text
            with fields_box:
                common = [f for f in state["fields"] if f.common]
                _fields(ui, common, state, check)
                with ui.expansion(f"advanced ({len(state['fields']) - len(common)} keys)",
                                  icon="tune").classes("w-full advanced-keys"):
                    _fields(ui, [f for f in state["fields"] if not f.common], state, check)
            robot_input = state["inputs"].get(f"problem.{s.defaults_key}")
            if robot_input is not None and (s.robot_defaults or s.robot_presets):
                robot_input.on_value_change(lambda e: robot_changed(e.value))
            check()

        def method_of(p: str | None) -> str:
            """The method a run of preset ``p`` (None: the defaults) gets on the chosen robot
            (gym: environment), whose defaults may choose it."""
            if p is None:
                return default_algorithm(s, state.get("robot") or "")
            return str(actions.check_new_run(study, p, actions.robot_sets(
                study, state.get("robot"))).algorithm.name)

        def layers(robot: str, p: str | None) -> tuple:
            """What the fields of ``robot`` under preset ``p`` are made of: its defaults and
            the preset's own setting on it (the preset's, where it has none of its own)."""
            own, robot = s.robot_presets.get(p or "", {}), defaults_entry(s, robot)
            return s.robot_defaults.get(robot), own.get(robot, s.presets.get(p or ""))

        def robot_changed(value: object) -> None:
            """A robot with other defaults of its own (``Study.robot_defaults``; ``""``: the
            study's own robot; or gym's environment, ``Study.defaults_key``) than the one
            shown rebuilds the fields for it, as a preset does: the form shows what the run
            will use."""
            value = str(value or "")
            shown = state.get("robot") or ""
            old = method_of(preset.value or None)
            state["robot"] = value or None  # kept by the next rebuild, whatever rebuilds
            problem = cloned.get("problem")
            if isinstance(problem, dict):  # the chosen robot, not the cloned run's
                cloned["problem"] = {k: v for k, v in problem.items() if k != s.defaults_key}
            if layers(value, preset.value) != layers(shown, preset.value):
                new = method_of(preset.value or None)  # its method (gym: Hopper's CMA-ES)
                if alg.value == old != new:
                    alg.set_value(new)  # its handler rebuilds the fields
                else:
                    rebuild()

        async def go() -> None:
            from nicegui import run

            if not check():
                return
            start.disable()
            try:  # waits until the run wrote its config.toml: off the event loop
                started = await run.io_bound(actions.start_run, root, study,
                                             preset.value or None, current_sets(),
                                             (run_name.value or "").strip(),
                                             parse_tags(run_tags.value or ""))
            except InputError as e:
                start.enable()
                error_top.set_text(f"error: {e}")
                return
            if started is None:  # cancelled, or the studio is stopping
                start.enable()
                return
            out, _proc = started
            ui.navigate.to(f"/run?name={quote(out.relative_to(root).as_posix())}")

        def preset_changed() -> None:
            p = preset.value or None
            if p in s.preset_studies:
                ui.navigate.to(f"/new?study={quote(s.preset_studies[p])}")
                return
            name = method_of(p)
            if alg.value != name:
                alg.set_value(name)  # its handler rebuilds the fields
            else:
                rebuild()

        preset.on_value_change(lambda _: preset_changed())
        alg.on_value_change(lambda _: rebuild())
        start.on_click(go)
        if isinstance(robot0, str) and layers(robot0, preset0) != layers("", preset0):
            state["robot"] = robot0  # a cloned run's robot with other defaults: shown with them
        rebuild()


def _cloned(root: Path, name: str) -> tuple[dict, str]:
    """The config table of run ``name`` to start the form from, and a line saying so (or
    why not: the form then starts from the defaults)."""
    from evomotion.run.config import as_now
    from evomotion.studio.data import read_config, resolve_run

    try:
        text, table = read_config(resolve_run(root, name))
    except InputError as e:
        return {}, f"not cloned: {e}"
    if not table:
        return {}, f"not cloned: {name}'s config.toml does not parse ({text[:80]})"
    return as_now(table), (f"cloned from {name}: its preset, algorithm and every value it set "
                           "are filled in (the fields that differ from the defaults)")


def _fields(ui, fields: list, state: dict, check) -> None:
    """The inputs of ``fields`` by section: a checkbox, a select (a registry's names; free
    text where other values are allowed) or a text input, each with its documentation as a
    hint and its own error line."""
    for sec in ("run", "algorithm", "problem"):
        group = [f for f in fields if f.key.startswith(sec + ".")]
        if not group:
            continue
        ui.label(f"[{sec}]").classes("font-mono font-bold mt-2")
        with ui.grid(columns=3).classes("w-full gap-x-6"):
            for f in group:
                with ui.column().classes("gap-0"):
                    hint = f.doc + (f" (exactly {f.value})" if f.shown != f.value
                                    and f.kind == "float" else "")
                    if f.kind == "bool":
                        w = ui.checkbox(f.key, value=state["clone_values"].get(
                            f.key, f.shown) == "true")
                        if hint:
                            w.tooltip(hint)
                    elif f.choices:
                        v = state["clone_values"].get(f.key, f.shown)
                        opts = list(dict.fromkeys([*f.choices, f.shown, v]))
                        w = ui.select(opts, value=v, label=f.key,
                                      with_input=f.free,
                                      new_value_mode="add-unique" if f.free else None)
                    else:
                        w = ui.input(f.key, value=state["clone_values"].get(f.key, f.shown))
                    if hint and f.kind != "bool":
                        w.props["hint"] = hint  # a dict item: no quoting of the text
                    w.classes("w-full").props(f"data-key={f.key}")
                    w.on_value_change(lambda _: check())
                    state["inputs"][f.key] = w
                    state["errors"][f.key] = ui.label().classes(
                        "text-red-700 text-xs field-error")


def _quote(a: str) -> str:
    import shlex

    return shlex.quote(a)
