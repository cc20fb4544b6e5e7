"""``kick-plan.png``: ball, inflated circle, goal, candidate kick points (coloured by
``C_kick``), the chosen point, the Bézier approach and the turn-walk-align baseline."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from evomotion.outfile import save_figure  # noqa: E402
from evomotion.studies.biped_kick.planning import (  # noqa: E402
    WalkModel,
    baseline_time,
    bezier,
    bezier_time,
    plan_kick,
)

BALL_RADIUS_M = 0.05


def plot_kick_plan(robot: np.ndarray, ball: np.ndarray, goal: np.ndarray, out_png: Path,
                   radius_m: float = 0.2, walk: WalkModel = WalkModel()) -> dict[str, float]:
    """Draw the plan; returns the lengths and times of both paths."""
    robot, ball, goal = (np.asarray(v, dtype=float) for v in (robot, ball, goal))
    plan = plan_kick(robot, ball, goal, radius_m)
    path = bezier(plan.control_points, np.linspace(0, 1, 200))
    bz_len, bz_t = bezier_time(plan.control_points, walk)
    bl_len, bl_t = baseline_time(robot, plan, walk)
    fig, ax = plt.subplots(figsize=(7, 5), dpi=110)
    centre = (ball[0], ball[1])
    ax.add_patch(plt.Circle(centre, radius_m, fill=False, ls="--", color="0.5",
                            label=f"ball inflated by R = {radius_m:.2f} m"))
    ax.add_patch(plt.Circle(centre, BALL_RADIUS_M, color="orange", label="ball"))
    cand_x, cand_y = plan.candidates.T
    sc = ax.scatter(cand_x, cand_y, c=plan.cost, cmap="viridis", s=18, zorder=3)
    fig.colorbar(sc, ax=ax, label="C_kick", shrink=0.6)
    ax.plot(*plan.kick_point, "r*", ms=14, zorder=4, label="chosen kick point")
    ax.plot(*path.T, "b-", lw=2, label=f"Bézier: {bz_len:.2f} m, {bz_t:.1f} s")
    ax.plot(*plan.control_points.T, "b:", marker="o", ms=4, alpha=0.6, label="control points")
    ax.plot([robot[0], plan.kick_point[0]], [robot[1], plan.kick_point[1]], "m--", lw=1.5,
            label=f"turn-walk-align: {bl_len:.2f} m, {bl_t:.1f} s")
    ax.plot([ball[0], goal[0]], [ball[1], goal[1]], color="0.7", lw=1)
    ax.plot(*goal, "ks", ms=10, label="goal centre")
    ax.arrow(robot[0], robot[1], 0.25 * np.cos(robot[2]), 0.25 * np.sin(robot[2]),
             width=0.02, color="k", label="robot")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.set_title(f"Kick plan (speed {walk.speed_m_s} m/s, turn {walk.turn_rad_s} rad/s)")
    ax.legend(fontsize=7, loc="best")
    fig.tight_layout()
    try:
        save_figure(fig, Path(out_png), "kick plan")
    finally:
        plt.close(fig)
    return {"bezier_length_m": bz_len, "bezier_time_s": bz_t,
            "baseline_length_m": bl_len, "baseline_time_s": bl_t}
