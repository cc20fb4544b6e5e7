"""Pictures after paper 001's figure 2: obstacles red, start green, targets orange, cells not
reachable from the start black, wrist-candidate cells light blue; the best limb blue and the
best feasible one green. ``best.gif`` animates the best limb over the generations."""

from __future__ import annotations

from pathlib import Path
from typing import Any, cast

import matplotlib

matplotlib.use("Agg")
import imageio.v2 as imageio  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402
from matplotlib.colors import ListedColormap  # noqa: E402
from numpy.typing import ArrayLike  # noqa: E402

from evomotion.outfile import atomic_output, save_figure  # noqa: E402
from evomotion.studies.arm_ik.kinematics import forward  # noqa: E402
from evomotion.studies.arm_ik.problem import ArmIKProblem  # noqa: E402
from evomotion.studies.view import Frames, RunFiles  # noqa: E402


def _draw_board(ax, prob: ArmIKProblem) -> None:
    scn, wm = prob.scn, prob.wrist_map
    layer = np.where(~wm.reachable, 1, np.where(wm.candidate, 2, 0))
    ax.imshow(layer, origin="lower", extent=(0, wm.reachable.shape[1] * wm.cell, 0,
              wm.reachable.shape[0] * wm.cell), interpolation="nearest",
              cmap=ListedColormap(["white", "black", "#add8e6"]), vmin=0, vmax=2)
    for p in scn.obstacles:
        ax.plot(p[:, 0], p[:, 1], color="red", lw=2)
    ax.plot(*scn.start, "o", color="green", ms=8)
    ax.plot(scn.targets[:, 0], scn.targets[:, 1], "o", color="orange", ms=8)
    ax.set_xlim(0, scn.width)
    ax.set_ylim(0, scn.height)
    ax.set_aspect("equal")


def _draw_limb(ax, prob: ArmIKProblem, genome: np.ndarray, color: str, label: str) -> None:
    pose = forward(prob.scn, prob.layout, genome[None])
    arm = pose.arm_joints[0]
    ax.plot(arm[:, 0], arm[:, 1], "-o", color=color, lw=2.5, ms=3, label=label)
    for j, b in enumerate(prob.layout.finger_bones):
        f = pose.finger_joints[0, j, : b + 1]
        ax.plot(f[:, 0], f[:, 1], "-o", color=color, lw=1.5, ms=2, alpha=0.8)


def _figure(prob: ArmIKProblem):
    scn = prob.scn
    w = 7.0
    # a board of any shape fits a figure of at most 7 x 20 inches (the axes keep its aspect)
    return plt.subplots(figsize=(w, min(20.0, max(2.5, w * scn.height / scn.width + 0.6))),
                        dpi=100)


def save_board(prob: ArmIKProblem, best: np.ndarray, best_feasible: np.ndarray | None,
               path: Path, title: str = "") -> None:
    """``board.png``: the heuristic map, the best limb (blue) and best feasible limb (green)."""
    fig, ax = _figure(prob)
    _draw_board(ax, prob)
    _draw_limb(ax, prob, best, "blue", "best")
    if best_feasible is not None:
        _draw_limb(ax, prob, best_feasible, "green", "best feasible")
    ax.legend(loc="upper right", fontsize=7)
    ax.set_title(title or prob.scn.name, fontsize=9)
    fig.tight_layout()
    try:
        save_figure(fig, path, "board picture")
    finally:
        plt.close(fig)


def population_figure(prob: ArmIKProblem, pop: np.ndarray, best: np.ndarray, title: str = ""):
    """The board with every limb of a population (grey) and its best (blue), as paper 001's GUI
    showed a generation."""
    fig, ax = _figure(prob)
    _draw_board(ax, prob)
    for g in pop:
        pose = forward(prob.scn, prob.layout, g[None])
        arm = pose.arm_joints[0]
        ax.plot(arm[:, 0], arm[:, 1], "-", color="0.55", lw=0.8, alpha=0.5)
    _draw_limb(ax, prob, best, "blue", "best of the generation")
    ax.legend(loc="upper right", fontsize=7)
    ax.set_title(title or prob.scn.name, fontsize=9)
    fig.tight_layout()
    return fig


def save_gif(prob: ArmIKProblem, history: np.ndarray, path: Path, frames: int = 30,
             fps: float = 5.0) -> None:
    """Animated GIF of the best limb at ``frames`` generations spread over ``history``."""
    idx = np.unique(np.linspace(0, history.shape[0] - 1, max(1, frames)).round().astype(int))
    fig, ax = _figure(prob)
    images: list[ArrayLike] = []
    for g in idx:
        ax.clear()
        _draw_board(ax, prob)
        _draw_limb(ax, prob, history[g], "blue", "best")
        ax.set_title(f"{prob.scn.name}: generation {g}", fontsize=9)
        fig.canvas.draw()
        images.append(np.asarray(fig.canvas.buffer_rgba())[..., :3].copy())
    plt.close(fig)
    with atomic_output(path, "animation", suffix=".tmp.gif") as tmp:
        imageio.mimsave(tmp, images, duration=1.0 / fps, loop=0)


#: the stats.csv columns printed under a generation's picture in the studio
FRAME_STATS = ("phase", "mean_objective", "var_objective", "mean_intersections",
               "var_intersections", "originality", "feasible_fraction", "best_objective")


def studio_frames(files: RunFiles) -> Frames:
    """The studio's view of an arm-ik run: the board with each recorded generation's
    population and best limb, and the paper's statistics of that generation."""
    hist = files.history()
    prob = cast(ArmIKProblem, files.problem())  # an arm-ik run's (this study's view)
    stats = files.stats()
    gens = stats.get("generation", [])

    def draw(k: int) -> tuple[Any, str]:
        g, pop, fit = hist[k]
        best = pop[int(np.nanargmin(np.where(np.isfinite(fit), fit, np.inf)))]
        fig = population_figure(prob, pop, best, f"generation {g}: {len(pop)} limbs")
        row = gens.index(g) if g in gens else None
        shown = [f"{key} {stats[key][row]:.4g}" for key in FRAME_STATS
                 if row is not None and key in stats and stats[key][row] is not None]
        return fig, f"generation {g}: {', '.join(shown)}"

    return Frames(len(hist), draw)
