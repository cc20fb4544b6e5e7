"""Pictures of a walking plan: ``plan.png`` (the path) and ``plan.gif`` (the gait).

Both read only the plan.json document, so they draw any plan that passes the checker.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

LEG_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red")


def _corners(doc: dict[str, Any], body: list[float]) -> np.ndarray:
    a2, b2 = doc["model"]["a"] / 2, doc["model"]["b"] / 2
    c, s = math.cos(body[2]), math.sin(body[2])
    local = np.array([[-a2, b2], [-a2, -b2], [a2, -b2], [a2, b2], [-a2, b2]])
    return np.stack([body[0] + c * local[:, 0] - s * local[:, 1],
                     body[1] + s * local[:, 0] + c * local[:, 1]], axis=1)


def _draw_state(ax: Any, doc: dict[str, Any], st: dict[str, Any], alpha: float = 1.0,
                support: bool = False) -> None:
    corners = _corners(doc, st["body"])
    ax.plot(corners[:, 0], corners[:, 1], "k-", lw=1.2, alpha=alpha)
    feet = np.array(st["feet"])
    for leg in range(4):
        hx, hy = corners[leg]
        ax.plot([hx, feet[leg, 0]], [hy, feet[leg, 1]], color=LEG_COLOURS[leg], lw=1.5,
                alpha=alpha)
        ax.plot(*feet[leg], "o", color=LEG_COLOURS[leg], ms=4, alpha=alpha)
    b = st["body"]
    # walking-direction arrow (body -Y for sense -1, +Y otherwise)
    sense = -1.0 if doc.get("sense", -1) < 0 else 1.0
    ax.arrow(b[0], b[1], -sense * 0.8 * math.sin(b[2]), sense * 0.8 * math.cos(b[2]),
             head_width=0.25, color="k", alpha=alpha)
    if support:
        rule = st["rule"]
        idx = [k for k in range(4) if not (rule >= 4 and k == (rule - 4) % 4)]
        poly = feet[idx + [idx[0]]]
        ax.fill(poly[:, 0], poly[:, 1], color="tab:gray", alpha=0.2)
        ax.plot(poly[:, 0], poly[:, 1], color="tab:gray", lw=0.8)


def _frame_limits(doc: dict[str, Any]) -> tuple[float, float, float, float]:
    pts = np.array([f for st in doc["states"] for f in st["feet"]] + [doc["goal"]])
    lo, hi = pts.min(axis=0) - 1.5, pts.max(axis=0) + 1.5
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


def _decor(ax: Any, doc: dict[str, Any]) -> None:
    gx, gy = doc["goal"]
    ax.add_patch(plt.Circle((gx, gy), doc["goal_tolerance"], color="tab:green", alpha=0.4))
    ax.plot(gx, gy, "*", color="tab:green", ms=14)
    zone = doc.get("zone")
    if zone:
        ax.add_patch(plt.Circle((zone["x"], zone["y"]), zone["radius"], color="tab:red",
                                alpha=0.25))
    x0, x1, y0, y1 = _frame_limits(doc)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)


def plot_plan(doc: dict[str, Any], out_png: str | Path, every: int = 0) -> None:
    """The body path with the robot drawn every ``every`` states (0: about 12 drawings)."""
    states = doc["states"]
    every = every or max(1, len(states) // 12)
    fig, ax = plt.subplots(figsize=(7, 7))
    path = np.array([st["body"][:2] for st in states])
    ax.plot(path[:, 0], path[:, 1], "-", color="tab:purple", lw=1.5, label="body centre")
    for i in [*range(0, len(states), every), len(states) - 1]:
        _draw_state(ax, doc, states[i], alpha=0.35 if i < len(states) - 1 else 1.0)
    _decor(ax, doc)
    legs = sum(1 for st in states if st["rule"] >= 4)
    ax.set_title(f"{len(states)} states, {legs} leg moves (rule set {doc['rule_set']})")
    ax.legend(loc="best")
    fig.savefig(out_png, dpi=110, bbox_inches="tight")
    plt.close(fig)


def animate_plan(doc: dict[str, Any], out_gif: str | Path, max_frames: int = 150,
                 fps: float = 6.0) -> None:
    """The gait state by state: body, legs, support polygon (the swing triangle during a
    leg move), path so far and goal."""
    import imageio.v2 as imageio

    states = doc["states"]
    step = max(1, math.ceil(len(states) / max_frames))
    idx = [*range(0, len(states), step)]
    if idx[-1] != len(states) - 1:
        idx.append(len(states) - 1)
    fig, ax = plt.subplots(figsize=(5, 5), dpi=80)
    frames = []
    path = np.array([st["body"][:2] for st in states])
    for i in idx:
        ax.clear()
        ax.plot(path[: i + 1, 0], path[: i + 1, 1], "-", color="tab:purple", lw=1)
        _draw_state(ax, doc, states[i], support=True)
        _decor(ax, doc)
        ax.set_title(f"state {i}/{len(states) - 1}  rule {states[i]['rule']}  "
                     f"margin {states[i]['margin']:.2f}", fontsize=9)
        fig.canvas.draw()
        frames.append(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy())
    plt.close(fig)
    imageio.mimsave(out_gif, frames, duration=1.0 / fps, loop=0)
