"""Replays on a run's page beside its files' motions: the best of any recorded generation
(``StudyView.genome_motion``, with the last generation's best ghosted over it on request) and a
policy's closed-loop episode in a chosen unseen world and push (``StudyView.played``)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np

from evomotion.errors import InputError
from evomotion.studies.view import NothingYetError, RunFiles
from evomotion.studio.readers import one_line


def generations(ui, files: RunFiles, view: Any, scene: str) -> None:
    """The best individual of any recorded generation replayed in 3D (a slider over the
    generations of ``population.bin``)."""
    from evomotion.studio.nao3d import NaoPlayer

    ui.label("the best of each recorded generation").classes("font-bold mt-4")
    try:
        hist = files.history()
    except NothingYetError as e:
        ui.label(one_line(e)).classes("text-slate-600 generations-empty")
        return
    problem = files.problem()
    sense = getattr(problem, "sense", "max")
    box = ui.column().classes("w-full")
    caption = ui.label().classes("text-slate-600 generation-caption")

    def best(k: int) -> tuple[int, int, float, Any]:
        gen, pop, fit = hist[int(k)]
        f = np.where(np.isfinite(fit), fit, -np.inf if sense == "max" else np.inf)
        i = int(np.argmax(f) if sense == "max" else np.argmin(f))
        return gen, i, float(fit[i]), view.genome_motion(problem, pop[i])

    def show() -> None:
        gen, i, fit, motion = best(slider.value)
        text = f"generation {gen}: its best, fitness {fit:.6g} (individual {i} of " \
               f"{len(hist[int(slider.value)][2])})"
        last = None
        if ghost.value:  # the last recorded generation's best, translucent beside it
            last_gen, _, last_fit, last = best(len(hist) - 1)
            text += f"; ghost: generation {last_gen}'s best, fitness {last_fit:.6g}"
        caption.set_text(text)
        box.clear()
        with box:
            NaoPlayer(motion, scene=scene, analysis=False, ghost=last)

    with ui.row().classes("items-center"):
        slider = ui.slider(min=0, max=len(hist) - 1, value=len(hist) - 1,
                           on_change=lambda _: show()).classes("w-96 generation-step")
        ui.label(f"{len(hist)} generations recorded")
        ghost = ui.switch("ghost the last generation's best", value=False,
                          on_change=lambda _: show()).classes("generation-ghost")
    show()


#: the pushes the policy view offers (N s; "" the world's own)
PUSHES = {"": "the world's own push", **{str(p): f"{p:g} N s" for p in (0, 2, 3, 4, 5)}}


def played(ui, run_dir: Path, play: Any, scene: str) -> None:
    """The run's exported policy in an unseen perturbed world (any of ``compare``'s), its
    push chosen, shown as it happened in the 3D player with its motion analysis."""
    from evomotion.studio.nao3d import NaoPlayer

    ui.label("the exported policy in an unseen perturbed world").classes("font-bold mt-4")
    with ui.row().classes("items-end"):
        world = ui.number("world", value=0, min=0, max=9999, precision=0) \
            .classes("w-32 played-world")
        push = ui.select(PUSHES, value="", label="push").classes("w-56 played-push")
        go = ui.button("play", icon="play_arrow").classes("played-button")
    caption = ui.label().classes("text-slate-600 played-caption")
    box = ui.column().classes("w-full")

    async def show() -> None:
        from nicegui import run

        w = world.value if isinstance(world.value, int | float) else 0
        caption.set_text(f"playing world {int(w)} ...")
        go.disable()
        try:  # the episode is simulated off the event loop (other pages stay live)
            episode = await run.io_bound(play, run_dir, int(w),
                                         float(push.value) if push.value else None)
        except InputError as e:  # no policy yet, a world out of range: one line
            box.clear()
            caption.set_text(one_line(e))
            return
        finally:
            go.enable()
        if episode is None:  # cancelled, or the studio is stopping
            return
        caption.set_text(episode.caption)
        box.clear()
        with box:
            NaoPlayer(episode, scene=scene)

    go.on_click(show)
    ui.timer(0.0, show, once=True)
