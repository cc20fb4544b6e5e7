"""Drive a run's walk controller live from the page (issue 35): the keyboard or on-screen
sliders set the command (forward, sideways, turning), a button or a key pushes the robot, and
the simulation (:class:`~evomotion.sim.live_walk.LiveWalk`) runs on the server in real time,
its body poses drawn in 3D about 20 times a second.

Keys (while the page has focus): W / arrow up, S / arrow down: forward / backward at the
controller's largest command; A / arrow left, D / arrow right: turn left / right; Q / E: step
left / right; P or space: push; R: start again. A key held sets that component; released, it
returns to the slider's value. An on-screen joystick does the same with proportional commands
(up: forward, left/right: turn, or step sideways with its switch).
"""

from __future__ import annotations

import contextlib
import time
from pathlib import Path
from typing import Any

import numpy as np

TICK_S = 0.05
#: the NAO walk's torso height at the start (m, LiveWalk.height_m): the camera's unit
NAO_TORSO_HEIGHT_M = 0.281
KEYS = {"w": ("vx", 1), "arrowup": ("vx", 1), "s": ("vx", -1), "arrowdown": ("vx", -1),
        "a": ("yaw_rate", 1), "arrowleft": ("yaw_rate", 1), "d": ("yaw_rate", -1),
        "arrowright": ("yaw_rate", -1), "q": ("vy", 1), "e": ("vy", -1)}
DIRECTIONS = {"from behind (+x)": 0.0, "from the right (+y)": 90.0, "from the front (-x)": 180.0,
              "from the left (-y)": -90.0}


def drive_panel(ui, run_dir: Path, robot: str = "nao") -> None:
    """The drive view of ``run_dir``'s controller on ``robot`` (its config's ``problem.robot``,
    checked by the caller)."""
    from evomotion.sim.live_walk import LiveWalk
    from evomotion.studio.nao3d import _add_geom, geom_table

    if not (run_dir / "policy.json").exists():
        ui.label("no policy.json in this run yet (written at checkpoints)").classes("drive-empty")
        return
    walk = LiveWalk(run_dir, robot)
    names = list(walk.command_ranges)
    ui.label("drive the controller: W/S or arrows forward/back, A/D turn, Q/E sideways, "
             "P or space push, R restart").classes("font-bold drive-help")
    sliders: dict[str, Any] = {}
    held: dict[str, float] = {}
    with ui.row().classes("items-center gap-6"):
        for n in names:
            lo, hi = walk.command_ranges[n]
            with ui.column().classes("gap-0"):
                unit = "rad/s" if n == "yaw_rate" else "m/s"
                ui.label(f"{n} ({unit})").classes("text-sm")
                sliders[n] = ui.slider(min=lo, max=hi, step=(hi - lo) / 40, value=0.0) \
                    .classes(f"w-48 drive-{n}").props("label")
        strength = ui.number("push (N s)", value=2.0, min=0.0, max=20.0, step=0.5) \
            .classes("w-28 drive-strength")
        direction = ui.select(list(DIRECTIONS), value="from behind (+x)", label="push") \
            .classes("w-48 drive-direction")
        ui.button("push", icon="back_hand", on_click=lambda: push()).classes("drive-push")
        ui.button("restart", icon="restart_alt", on_click=lambda: restart()) \
            .classes("drive-restart")
    def stick(e) -> None:
        """The on-screen joystick: up/down forward/back, left/right turn (or step sideways
        with the 'sideways' switch), scaled to the controller's ranges; released: stop."""
        if e.action == "end" or e.x is None or e.y is None:
            for n in ("vx", "vy", "yaw_rate"):
                held.pop(n, None)
            return
        turn = "vy" if sideways.value else "yaw_rate"
        for n, v in (("vx", float(e.y)), (turn, -float(e.x))):
            if n in walk.command_ranges:
                lo, hi = walk.command_ranges[n]
                held[n] = v * (hi if v > 0 else -lo)

    with ui.row().classes("items-center gap-6"):
        ui.joystick(on_move=stick, on_end=stick, color="#5470c6", size=90) \
            .classes("w-40 h-40 bg-slate-100 rounded drive-joystick")
        sideways = ui.switch("joystick left/right steps sideways").classes("drive-sideways")
    status = ui.label().classes("font-mono text-sm drive-status")
    geoms = geom_table(walk.model)
    bodies = sorted({g["body"] for g in geoms})
    camera = ui.scene.perspective_camera(fov=45, near=0.01, far=100)
    with ui.scene(width=640, height=420, grid=(20, 80), camera=camera,
                  background_color="#f4f6f8").classes("drive-scene") as scene:
        groups = []
        for b in bodies:
            with scene.group() as group:
                for g in geoms:
                    if g["body"] == b:
                        _add_geom(scene, g)
            groups.append(group)
    clock = {"wall0": time.monotonic(), "sim0": 0.0}

    def command() -> np.ndarray:
        return np.array([held.get(n, sliders[n].value) for n in names], float)

    def push() -> None:
        walk.push(float(strength.value or 0.0), DIRECTIONS[direction.value])

    def restart() -> None:
        walk.reset()
        clock.update(wall0=time.monotonic(), sim0=0.0)

    def on_key(e) -> None:
        key = str(getattr(e.key, "name", e.key)).lower()
        if e.action.keydown and not e.action.repeat:
            if key in ("p", " ", "space"):
                push()
            elif key == "r":
                restart()
        if key in KEYS and KEYS[key][0] in walk.command_ranges:
            n, sign = KEYS[key]
            if e.action.keydown:
                held[n] = walk.command_ranges[n][1] if sign > 0 else walk.command_ranges[n][0]
            elif e.action.keyup:
                held.pop(n, None)

    ui.keyboard(on_key=on_key, ignore=["input", "select", "button", "textarea"])

    def tick() -> None:
        behind = (time.monotonic() - clock["wall0"]) - (walk.data.time - clock["sim0"])
        if behind > 0 and not walk.fell:
            walk.advance(command(), min(behind, 4 * TICK_S))
        d = walk.data
        batch = getattr(scene, "_batch_calls", None)  # NiceGUI's own batching
        with batch() if batch is not None else contextlib.nullcontext():
            for group, b in zip(groups, bodies, strict=True):
                group.move(*d.xpos[b].tolist()).rotate_R(d.xmat[b].reshape(3, 3).tolist())
        s = walk.status()
        x, y = d.xpos[walk.torso][:2]
        k = walk.height_m / NAO_TORSO_HEIGHT_M  # framed as the NAO is, at the robot's size
        scene.move_camera(x=x + 0.9 * k, y=y - 0.8 * k, z=0.6 * k, look_at_x=x, look_at_y=y,
                          look_at_z=0.25 * k, duration=0)
        status.set_text(
            f"t {s['t_s']:6.2f} s  x {s['x_m']:+.2f} m  y {s['y_m']:+.2f} m  heading "
            f"{s['heading_deg']:+.0f}°  |  v {s['vx_m_s']:+.2f} {s['vy_m_s']:+.2f} m/s, "
            f"{s['yaw_rate_rad_s']:+.2f} rad/s  |  command "
            + " ".join(f"{s['command_' + n]:+.2f}" for n in names)
            + ("  |  FELL: restart (R)" if s["fell"] else ""))

    ui.timer(TICK_S, tick)
