"""Plots of one kick: the foot trajectory (``plots/kick_foot.png``) and the ZMP against the
support polygon over time (``plots/kick_zmp.png``), from a recorded rollout
(:meth:`KickProblem.kicks` with ``keep=True``)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from evomotion.run.plots import _save
from evomotion.studies.biped_kick.motion import SETTLE_S, foot_trajectories, gene

PHASES = (("shift", "t_shift_s"), ("lift", "t_lift_s"), ("kick", "t_kick_s"),
          ("retract", "t_retract_s"), ("shift back", "t_shift_s"))
COLOURS = ("#dddddd", "#c6dbef", "#fdd0a2", "#c7e9c0", "#dddddd")


def phase_bounds(genome: np.ndarray) -> list[tuple[str, float, float]]:
    """(name, start s, end s) of the five phases, from the start of the motion."""
    g = np.atleast_2d(genome)
    t, out = SETTLE_S, []
    for name, key in PHASES:
        d = float(gene(g, key)[0])
        out.append((name, t, t + d))
        t += d
    return out


def _shade(ax, genome: np.ndarray, label: bool = False) -> None:
    for (name, a, b), c in zip(phase_bounds(genome), COLOURS, strict=True):
        ax.axvspan(a, b, color=c, alpha=0.6, lw=0, label=name if label else None)


def plot_foot(genome: np.ndarray, aim_rad: float, times: np.ndarray, sole_xyz: np.ndarray,
              out_stem: Path, feet: dict[str, np.ndarray] | None = None) -> list[Path]:
    """The commanded kicking ankle relative to the stance ankle (the stance foot stays put, so
    this is its path over the floor) and the simulated right sole (world), both from rest, in
    x, y, z against time; and the x-z side view. ``feet``: the commanded paths of
    ``times`` (default the NAO's, :func:`.motion.foot_trajectories`)."""
    import matplotlib.pyplot as plt

    if feet is None:
        feet = foot_trajectories(np.atleast_2d(genome), times, aim_rad)
    rel = feet["right"][0] - feet["left"][0]
    r = rel - rel[0]
    s = sole_xyz - sole_xyz[0]
    fig, axes = plt.subplots(1, 2, figsize=(11, 4), dpi=110,
                             gridspec_kw={"width_ratios": [1.6, 1]})
    ax = axes[0]
    _shade(ax, genome, label=True)
    for k, (name, c) in enumerate((("x (forward)", "C0"), ("y (left)", "C2"), ("z (up)", "C3"))):
        ax.plot(times, 100 * r[:, k], color=c, label=f"commanded {name}")
        ax.plot(times, 100 * s[:, k], color=c, ls="--", lw=1, label=f"sole, simulated {name}")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("displacement from rest (cm)")
    ax.set_title(f"Kicking foot, aim {np.degrees(aim_rad):+.0f} deg")
    ax.legend(fontsize=7, ncol=2, loc="upper left")
    ax = axes[1]
    seg = [(a, b) for _, a, b in phase_bounds(genome)]
    for (name, _), (a, b), c in zip(PHASES[1:4], seg[1:4], ("C0", "C1", "C2"), strict=True):
        m = (times >= a) & (times <= b)
        ax.plot(100 * r[m, 0], 100 * r[m, 2], color=c, lw=2, label=name)
    ax.plot(100 * s[:, 0], 100 * s[:, 2], color="0.4", ls="--", lw=1, label="sole, simulated")
    ax.set_xlabel("x forward (cm)")
    ax.set_ylabel("z up (cm)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("Side view: lift, kick, retract")
    ax.legend(fontsize=8)
    return _save(fig, out_stem)


def plot_zmp(genome: np.ndarray, times: np.ndarray, margin: np.ndarray, cop: np.ndarray,
             corners: np.ndarray, required_m: float, out_stem: Path) -> list[Path]:
    """CoP margin against time (with the required margin) and the top view: CoP path coloured
    by time over the support polygons at the phase boundaries."""
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(11, 4.2), dpi=110,
                             gridspec_kw={"width_ratios": [1.6, 1]})
    ax = axes[0]
    _shade(ax, genome, label=True)
    m = np.where(np.isfinite(margin), margin, np.nan)
    ax.plot(times, 1000 * m, "k-", lw=1.2, label="CoP margin")
    none = ~np.isfinite(margin)
    if none.any():
        ax.plot(times[none], np.zeros(none.sum()), "rx", ms=4, label="no sole contact")
    ax.axhline(1000 * required_m, color="r", ls="--", lw=1,
               label=f"required {1000 * required_m:.0f} mm")
    ax.set_xlabel("time (s)")
    ax.set_ylabel("margin inside support polygon (mm)")
    ax.set_title("ZMP (centre of pressure) stability margin")
    ax.legend(fontsize=7, loc="lower left")
    ax = axes[1]
    for (_, a, _), c in zip(phase_bounds(genome), ("0.6", "C0", "C1", "C2", "0.3"),
                            strict=True):
        i = min(int(np.searchsorted(times, a)), len(times) - 1)
        for k in range(0, 8, 4):  # each sole's rectangle, where it is in contact
            q = corners[i, k:k + 4][[0, 1, 3, 2, 0]]
            if np.isfinite(q).all():
                ax.plot(100 * q[:, 0], 100 * q[:, 1], color=c, lw=1)
    ok = np.isfinite(cop[:, 0])
    sc = ax.scatter(100 * cop[ok, 0], 100 * cop[ok, 1], c=times[ok], s=3, cmap="viridis")
    fig.colorbar(sc, ax=ax, label="time (s)", shrink=0.8)
    ax.set_xlabel("x (cm)")
    ax.set_ylabel("y (cm)")
    ax.set_aspect("equal", adjustable="datalim")
    ax.set_title("CoP path and support polygons")
    return _save(fig, out_stem)


def plot_progress(stats_csv: Path, floor_m: float, out_stem: Path) -> list[Path]:
    """Best objective so far and best of each generation against evaluations, feasible kicks
    only (the run's fitness plot also shows the infeasible ones, far below ``floor_m``)."""
    import matplotlib.pyplot as plt

    from evomotion.run.stats import read_stats

    s = read_stats(stats_csv)
    ev = s["evaluations"]
    fig, ax = plt.subplots(figsize=(7, 4), dpi=110)
    for key, style, label in (("best", "C0.", "best of the generation"),
                              ("best_so_far", "C3-", "best so far")):
        y = np.where(s[key] >= floor_m, s[key], np.nan)
        ax.plot(ev, y, style, ms=3, label=label)
    first = np.flatnonzero(s["best_so_far"] >= floor_m)
    if first.size:
        ax.axvline(ev[first[0]], color="0.5", ls=":", lw=1,
                   label=f"first feasible kick ({int(ev[first[0]])} evaluations)")
    ax.set_xlabel("evaluations")
    ax.set_ylabel("objective of feasible kicks (m)")
    ax.set_title("Kick search: feasible kicks only (ZMP, fall, NAO limits met)")
    ax.legend(fontsize=8)
    return _save(fig, out_stem)
