"""``path.png``: the map, the best path and the three models' optimal paths (dashed)."""

from __future__ import annotations

from pathlib import Path
from typing import Any, cast

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from evomotion.outfile import save_figure  # noqa: E402
from evomotion.studies.grid_path.maps import GridMap  # noqa: E402
from evomotion.studies.grid_path.problem import GridPathProblem  # noqa: E402
from evomotion.studies.grid_path.solvers import Solution  # noqa: E402
from evomotion.studies.view import Frames, RunFiles  # noqa: E402

STYLES = {"octile": ("tab:orange", (0, (5, 2))), "centres": ("tab:green", (0, (3, 2))),
          "free": ("tab:purple", (0, (1, 1.5)))}


def save_path_png(m: GridMap, best: np.ndarray, optima: dict[str, Solution], out: Path,
                  title: str = "", perpendiculars: np.ndarray | None = None) -> Path:
    """Draw ``best`` (``[k, 2]`` cell units) over the map with the optima; returns ``out``."""
    fig = path_figure(m, best, optima, title, perpendiculars)
    try:
        return save_figure(fig, out, "path picture", dpi=110)
    finally:
        plt.close(fig)


def path_figure(m: GridMap, best: np.ndarray, optima: dict[str, Solution], title: str = "",
                perpendiculars: np.ndarray | None = None):
    """The figure of :func:`save_path_png` (the studio shows it per generation)."""
    size = max(4.0, min(9.0, 0.45 * max(m.width, m.height)))
    fig, ax = plt.subplots(figsize=(size, min(20.0, size * m.height / m.width + 0.4)))
    ax.imshow(m.blocked, cmap="Greys", vmin=0, vmax=1.4, origin="lower",
              extent=(0, m.width, 0, m.height), interpolation="nearest")
    if max(m.width, m.height) <= 40:
        ax.set_xticks(range(m.width + 1), minor=True)
        ax.set_yticks(range(m.height + 1), minor=True)
        ax.grid(which="minor", color="0.85", lw=0.5)
    if perpendiculars is not None:
        for a, b in perpendiculars:
            ax.plot([a[0], b[0]], [a[1], b[1]], color="0.75", lw=0.6, zorder=1)
    for name, sol in optima.items():
        color, dash = STYLES.get(name, ("tab:gray", "--"))
        ax.plot(*sol.waypoints.T, color=color, ls=dash, lw=1.6, zorder=2,
                label=f"{name} optimum {sol.length:.4f}")
    length = float(np.hypot(*np.diff(best, axis=0).T).sum())
    ax.plot(*best.T, color="tab:red", lw=2.2, marker="o", ms=3, zorder=3,
            label=f"best path {length:.4f}")
    ax.plot(*m.start_xy, "s", color="tab:blue", ms=8, zorder=4)
    ax.plot(*m.goal_xy, "*", color="tab:blue", ms=12, zorder=4)
    ax.set_xlim(0, m.width)
    ax.set_ylim(0, m.height)
    ax.set_aspect("equal")
    ax.set_title(title or m.name, fontsize=10)
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.06), ncol=2, fontsize=8)
    fig.tight_layout()
    return fig


def studio_frames(files: RunFiles) -> Frames:
    """The studio's view of a grid-path run: the map with each recorded generation's best
    path."""
    hist = files.history()
    prob = cast(GridPathProblem, files.problem())  # a grid-path run's (this study's view)
    sign = -1.0 if getattr(prob, "sense", "min") == "max" else 1.0

    def draw(k: int) -> tuple[Any, str]:
        g, pop, fit = hist[k]
        i = int(np.nanargmin(np.where(np.isfinite(fit), sign * fit, np.inf)))
        path = prob.decode(pop[i:i + 1])[0]
        fig = path_figure(prob.map, np.asarray(path), {}, f"generation {g}: best path")
        return fig, f"generation {g}: best fitness {fit[i]:.6g}"

    return Frames(len(hist), draw)
