"""Fitness plots: max/mean/min per generation (the seeds' figures) and multi-run bands."""

from __future__ import annotations

from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from evomotion.errors import InputError  # noqa: E402
from evomotion.run.stats import read_stats  # noqa: E402


def plot_fitness(stats_csv: Path, out_stem: Path, title: str = "") -> list[Path]:
    """Max, mean and min fitness per generation; writes ``out_stem``.png and .svg."""
    s = read_stats(stats_csv)
    if not s:
        raise InputError(f"{stats_csv}: no generations recorded")
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    g = s["generation"]
    mark = "o" if len(g) <= 30 else None  # a short run (a few search batches) stays visible
    ax.plot(g, s["max"], label="max", color="tab:green", marker=mark)
    ax.plot(g, s["mean"], label="mean", color="tab:blue", marker=mark)
    ax.plot(g, s["min"], label="min", color="tab:red", marker=mark)
    ax.set_xlabel("generation")
    ax.set_ylabel("fitness")
    ax.set_title(title or Path(stats_csv).parent.name)
    ax.grid(alpha=0.3)
    ax.legend()
    return _save(fig, out_stem)


def plot_runs(stats_csvs: list[Path], out_stem: Path, column: str = "best_so_far",
              title: str = "") -> list[Path]:
    """Median and interquartile band of ``column`` against evaluations over several runs."""
    runs = [read_stats(p) for p in stats_csvs]
    runs = [r for r in runs if r]
    if not runs:
        raise InputError("no run has any recorded generation")
    grid = np.unique(np.concatenate([r["evaluations"] for r in runs]))
    ys = np.array([_step_interp(grid, r["evaluations"], r[column]) for r in runs])
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    med = np.nanmedian(ys, axis=0)
    q1, q3 = np.nanpercentile(ys, 25, axis=0), np.nanpercentile(ys, 75, axis=0)
    ax.plot(grid, med, color="tab:blue", label=f"median of {len(runs)} runs")
    ax.fill_between(grid, q1, q3, color="tab:blue", alpha=0.25, label="interquartile range")
    ax.set_xlabel("evaluations")
    ax.set_ylabel(column.replace("_", " "))
    ax.set_title(title)
    ax.grid(alpha=0.3)
    ax.legend()
    return _save(fig, out_stem)


def _step_interp(grid, x, y):
    idx = np.searchsorted(x, grid, side="right") - 1
    out = np.where(idx >= 0, y[np.clip(idx, 0, None)], np.nan)
    return out


def _save(fig, out_stem: Path) -> list[Path]:
    out_stem = Path(out_stem)
    out_stem.parent.mkdir(parents=True, exist_ok=True)
    paths = [out_stem.with_suffix(".png"), out_stem.with_suffix(".svg")]
    fig.tight_layout()
    for p in paths:
        fig.savefig(p, dpi=120)
    plt.close(fig)
    return paths
