"""Pictures of a walking plan: ``plan.png`` (the path) and ``plan.gif`` (the gait).

Both read only the plan.json / mission.json document, so they draw any plan that passes the
checker: the world (obstacles grey, no-step zones hatched orange, hidden obstacles dashed,
posts that appeared red), start and goal (and a goal that moved), the body path, the robot
every few states, landing errors and slips, axes in the paper's units and a legend; the GIF
steps state by state with the rule's name and the support polygon (the swing triangle
during a leg move).
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any, cast

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.backends.backend_agg import FigureCanvasAgg  # noqa: E402
from matplotlib.patches import Patch, Polygon  # noqa: E402
from numpy.typing import ArrayLike  # noqa: E402

from evomotion.errors import InputError  # noqa: E402
from evomotion.outfile import atomic_output, save_figure  # noqa: E402
from evomotion.studies.quadruped_plan.rules.rules import is_leg_rule  # noqa: E402
from evomotion.studies.view import Frames, NothingYetError, RunFiles  # noqa: E402

LEG_COLOURS = ("tab:blue", "tab:orange", "tab:green", "tab:red")
LEG_SHORT = ("FL", "RL", "RR", "FR")


def rule_name(rule: int, event: str = "") -> str:
    """A rule of paper 003 (or a disturbance) in words."""
    if event and event != "start":
        return f"disturbance: {event}"
    if rule == 0:
        return "start"
    if rule == 1:
        return "1 rotate to the goal heading"
    if rule == 2:
        return "2 translate b/3"
    if rule == 3:
        return "3 translate max"
    if 28 <= rule <= 31:
        return f"{rule} shift the body to free leg {LEG_SHORT[rule - 28]}"
    if rule == 32:
        return "32 step back (recovery)"
    leg = LEG_SHORT[(rule - 4) % 4]
    what = ("max length, rear edge", "mid length, nominal angle", "max length",
            "min length", "rear edge", "front edge")[(rule - 4) // 4]
    return f"{rule} leg {leg}: {what}"


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
    sense = -1.0 if doc.get("sense", -1) < 0 else 1.0  # walking direction: body -Y or +Y
    ax.arrow(b[0], b[1], -sense * 0.8 * math.sin(b[2]), sense * 0.8 * math.cos(b[2]),
             head_width=0.25, color="k", alpha=alpha)
    if support:
        rule = st["rule"]
        idx = [k for k in range(4) if not (is_leg_rule(rule) and k == (rule - 4) % 4)]
        poly = feet[idx + [idx[0]]]
        ax.fill(poly[:, 0], poly[:, 1], color="tab:gray", alpha=0.2)
        ax.plot(poly[:, 0], poly[:, 1], color="tab:gray", lw=0.8)


def _draw_world(ax: Any, doc: dict[str, Any], upto: int | None = None) -> list:
    """Obstacles and no-step zones (those existing at state ``upto``); legend handles."""
    world = doc.get("world")
    handles: list[Any] = []
    if not world:
        return handles
    kinds = set()
    for p in world["polygons"]:
        pts = np.array(p["points"])
        appeared = p.get("from", 0) > 0
        if upto is not None and p.get("from", 0) > upto:
            continue
        if p["kind"] == "nostep":
            ax.add_patch(Polygon(pts, closed=True, facecolor="tab:orange", alpha=0.25,
                                 hatch="//", edgecolor="tab:orange"))
            kinds.add("nostep")
        elif appeared:
            ax.add_patch(Polygon(pts, closed=True, facecolor="tab:red", alpha=0.5))
            kinds.add("appeared")
        elif p.get("hidden"):
            ax.add_patch(Polygon(pts, closed=True, facecolor="0.6", alpha=0.6, ls="--",
                                 edgecolor="k"))
            kinds.add("hidden")
        else:
            ax.add_patch(Polygon(pts, closed=True, facecolor="0.45", alpha=0.8))
            kinds.add("obstacle")
    labels = {"obstacle": ("0.45", "obstacle (body may not cross)"),
              "hidden": ("0.6", "obstacle hidden until in view"),
              "appeared": ("tab:red", "obstacle that appeared"),
              "nostep": ("tab:orange", "no-step zone (feet)")}
    for k in ("obstacle", "hidden", "appeared", "nostep"):
        if k in kinds:
            handles.append(Patch(color=labels[k][0], alpha=0.6, label=labels[k][1]))
    return handles


def _frame_limits(doc: dict[str, Any]) -> tuple[float, float, float, float]:
    if doc.get("world"):
        x0, y0, x1, y1 = doc["world"]["bounds"]
        return x0, x1, y0, y1
    pts = np.array([f for st in doc["states"] for f in st["feet"]] + [doc["goal"]])
    lo, hi = pts.min(axis=0) - 1.5, pts.max(axis=0) + 1.5
    return float(lo[0]), float(hi[0]), float(lo[1]), float(hi[1])


def _figsize(doc: dict[str, Any], width: float) -> tuple[float, float]:
    """A figure as wide as ``width`` inches with the world's aspect (plus room for text)."""
    x0, x1, y0, y1 = _frame_limits(doc)
    return width, min(1.4 * width, max(0.45 * width, width * (y1 - y0) / (x1 - x0) + 1.2))


def _decor(ax: Any, doc: dict[str, Any], upto: int | None = None) -> list:
    handles = _draw_world(ax, doc, upto)
    start = doc["states"][0]["body"]
    handles.append(ax.plot(start[0], start[1], "s", color="tab:blue", ms=9,
                           label="start")[0])
    goals = doc.get("goal_history") or [{"goal": doc["goal"], "from": 0}]
    current = [g for g in goals if upto is None or g["from"] <= upto][-1]
    for g in goals:
        if g is not current and (upto is None or g["from"] <= upto):
            handles.append(ax.plot(*g["goal"], "*", color="0.6", ms=12,
                                   label="goal before it moved")[0])
    gx, gy = current["goal"]
    ax.add_patch(plt.Circle((gx, gy), doc["goal_tolerance"], color="tab:green", alpha=0.4))
    handles.append(ax.plot(gx, gy, "*", color="tab:green", ms=14, label="goal")[0])
    zone = doc.get("zone")
    if zone:
        ax.add_patch(plt.Circle((zone["x"], zone["y"]), zone["radius"], color="tab:red",
                                alpha=0.25))
        handles.append(Patch(color="tab:red", alpha=0.25, label="exclusion zone"))
    x0, x1, y0, y1 = _frame_limits(doc)
    ax.set_xlim(x0, x1)
    ax.set_ylim(y0, y1)
    ax.set_aspect("equal")
    ax.grid(alpha=0.3)
    ax.set_xlabel("x [paper units]")
    ax.set_ylabel("y [paper units]")
    return handles


def plot_plan(doc: dict[str, Any], out_png: str | Path, every: int = 0) -> None:
    """The body path with the robot drawn every ``every`` states (0: about 12 drawings)."""
    states = doc["states"]
    every = every or max(1, len(states) // 12)
    fig, ax = plt.subplots(figsize=_figsize(doc, 8.0))
    handles = _decor(ax, doc)
    path = np.array([st["body"][:2] for st in states])
    handles.insert(0, ax.plot(path[:, 0], path[:, 1], "-", color="tab:purple", lw=1.5,
                              label="body centre")[0])
    for i in [*range(0, len(states), every), len(states) - 1]:
        _draw_state(ax, doc, states[i], alpha=0.35 if i < len(states) - 1 else 1.0)
    events = [st for st in states if st.get("event") not in (None, "", "start")]
    if events:
        pts = np.array([st["body"][:2] for st in events])
        handles.append(ax.plot(pts[:, 0], pts[:, 1], "x", color="tab:red", ms=6,
                               label=f"landing error / slip ({len(events)})")[0])
    counts: dict[int, int] = {}
    for st in states[1:]:
        if st["rule"]:
            counts[st["rule"]] = counts.get(st["rule"], 0) + 1
    top = sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))[:8]
    text = "rules used\n" + "\n".join(f"{n:>3} x {rule_name(r)}" for r, n in top)
    if len(counts) > len(top):
        text += f"\n    ... {len(counts) - len(top)} more"
    ax.text(0.99, 0.01, text, transform=ax.transAxes, ha="right", va="bottom", fontsize=6,
            multialignment="left",
            family="monospace", bbox={"facecolor": "white", "alpha": 0.8, "lw": 0.5})
    legs = sum(1 for st in states if is_leg_rule(st["rule"]))
    moves = len(states) - 1 - len(events)
    what = "executed walk" if doc.get("executed") else "plan"
    ax.set_title(f"{what}: {moves} transitions, {legs} leg moves (rule set "
                 f"{doc['rule_set']})" + (f" in {doc['world']['name']}" if doc.get("world")
                                          else ""))
    ax.legend(handles=handles, loc="upper left", fontsize=7, framealpha=0.85)
    try:
        save_figure(fig, out_png, "plan picture", dpi=110, bbox_inches="tight")
    finally:
        plt.close(fig)


def step_figure(doc: dict[str, Any], k: int):
    """State ``k`` of a plan or executed walk: the world, the path so far, the robot with its
    support polygon, and the rule that led to it (the studio steps through these)."""
    states = doc["states"]
    k = max(0, min(int(k), len(states) - 1))
    fig, ax = plt.subplots(figsize=_figsize(doc, 7.0))
    handles = _decor(ax, doc, upto=k)
    path = np.array([st["body"][:2] for st in states[:k + 1]])
    handles.insert(0, ax.plot(path[:, 0], path[:, 1], "-", color="tab:purple", lw=1.5,
                              label="body centre")[0])
    _draw_state(ax, doc, states[k], support=True)
    st = states[k]
    what = rule_name(st["rule"], st.get("event", "")) if k else "start"
    ax.set_title(f"state {k} of {len(states) - 1}: {what}", fontsize=10)
    ax.legend(handles=handles, loc="upper left", fontsize=7, framealpha=0.85)
    return fig


def animate_plan(doc: dict[str, Any], out_gif: str | Path, max_frames: int = 150,
                 fps: float = 6.0) -> None:
    """The gait state by state: body, legs, support polygon (the swing triangle during a
    leg move), path so far, world and goal, the rule's name."""
    import imageio.v2 as imageio

    states = doc["states"]
    step = max(1, math.ceil(len(states) / max_frames))
    idx = [*range(0, len(states), step)]
    if idx[-1] != len(states) - 1:
        idx.append(len(states) - 1)
    fig, ax = plt.subplots(figsize=_figsize(doc, 6.0), dpi=80)
    frames: list[ArrayLike] = []
    canvas = cast(FigureCanvasAgg, fig.canvas)  # the Agg backend (matplotlib.use above)
    path = np.array([st["body"][:2] for st in states])
    for i in idx:
        ax.clear()
        _decor(ax, doc, upto=i)
        ax.plot(path[: i + 1, 0], path[: i + 1, 1], "-", color="tab:purple", lw=1)
        _draw_state(ax, doc, states[i], support=True)
        st = states[i]
        ax.set_title(f"state {i}/{len(states) - 1}: {rule_name(st['rule'], st.get('event', ''))}"
                     f"\nstability margin {st['margin']:.2f}", fontsize=9)
        canvas.draw()
        frames.append(np.asarray(canvas.buffer_rgba())[..., :3].copy())
    plt.close(fig)
    with atomic_output(out_gif, "plan animation", suffix=".tmp.gif") as tmp:
        imageio.mimsave(tmp, frames, duration=1.0 / fps, loop=0)


def studio_frames(files: RunFiles) -> Frames:
    """The studio's view of a quadruped-plan run: its mission (or plan) state by state, with
    the rule names and the support polygon (the paper's viewer)."""
    name = next((n for n in ("mission.json", "plan.json") if (files.run_dir / n).exists()), None)
    if name is None:
        raise NothingYetError("no plan.json or mission.json: the search found no plan (yet)")
    doc = files.json(name, "plan")
    if not (isinstance(doc, dict) and isinstance(doc.get("states"), list) and doc["states"]):
        raise InputError(f"{files.run_dir / name}: expected a plan with a non-empty list of "
                         "states")
    return Frames(len(doc["states"]), lambda k: (step_figure(doc, k), f"state {k}"),
                  label="transition", title=f"{name}: {len(doc['states']) - 1} transitions")
