"""Fitness plots: max/mean/min per generation (the papers' figures) and multi-run bands."""

from __future__ import annotations

import warnings
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from evomotion.errors import InputError  # noqa: E402
from evomotion.outfile import save_figure  # noqa: E402
from evomotion.run.stats import read_stats, step_values  # noqa: E402


def plot_fitness(stats_csv: Path, out_stem: Path, title: str = "") -> list[Path]:
    """Max, mean and min fitness per generation; writes ``out_stem``.png and .svg."""
    s = read_stats(stats_csv)
    if not s:
        raise InputError(f"{stats_csv}: no generations recorded")
    _columns(s, stats_csv, ("generation", "max", "mean", "min"))
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
    for r, p in zip(runs, stats_csvs, strict=True):
        if r:
            _columns(r, p, ("evaluations", column))
    runs = [r for r in runs if r]
    if not runs:
        raise InputError("no run has any recorded generation")
    grid = np.unique(np.concatenate([r["evaluations"] for r in runs]))
    ys = np.array([step_values(grid, r["evaluations"], r[column]) for r in runs])
    fig, ax = plt.subplots(figsize=(6.4, 4.0))
    with warnings.catch_warnings(), np.errstate(invalid="ignore"):
        # a run not started yet at an evaluation count is NaN there, one without a finite
        # fitness inf (inf - inf inside the percentile): a gap in the band, no warning
        warnings.simplefilter("ignore", RuntimeWarning)
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


def _save(fig, out_stem: Path, tight: bool = True) -> list[Path]:
    out_stem = Path(out_stem)
    paths = [out_stem.with_suffix(".png"), out_stem.with_suffix(".svg")]
    try:
        if tight:
            fig.tight_layout()
        for p in paths:
            save_figure(fig, p, "plot", mkdir=True, dpi=120)
    finally:
        plt.close(fig)
    return paths


def _columns(s: dict, stats_csv: Path, names: tuple[str, ...]) -> None:
    missing = [c for c in names if c not in s]
    if missing:
        raise InputError(f"{stats_csv}: expected the columns {', '.join(names)} in its header "
                         f"line, missing {', '.join(missing)}")


def plot_qd(stats_csv: Path, out_stem: Path, title: str = "") -> list[Path]:
    """Coverage, QD-score, best objective and archive size against evaluations (the
    ``stats.csv`` columns of a quality-diversity run)."""
    s = read_stats(stats_csv)
    if not s or not {"coverage", "qd_score", "qd_best", "evaluations"} <= set(s):
        raise InputError(f"{stats_csv}: no quality-diversity columns (coverage, qd_score, "
                         "qd_best)")
    fig, axes = plt.subplots(1, 3, figsize=(11.0, 3.4))
    e = s["evaluations"]
    for ax, key, label in zip(axes, ("coverage", "qd_score", "qd_best"),
                              ("coverage (filled / cells)", "QD-score", "best objective"),
                              strict=True):
        ax.plot(e, s[key], color="tab:blue")
        ax.set_xlabel("evaluations")
        ax.set_ylabel(label)
        ax.grid(alpha=0.3)
    axes[0].set_title(title or Path(stats_csv).parent.name)
    return _save(fig, out_stem)


def plot_archive(archive_npz: Path, out_stem: Path, title: str = "") -> list[Path]:
    """Heat map of the elites' objective over the first two measures; with three or more
    measures one panel per slice of the third (the best elite of the others shown)."""
    from evomotion.run.archive_file import read_archive

    a = read_archive(archive_npz)
    m = a.lower.size
    names = a.measure_names
    if m == 1:
        fig, ax = plt.subplots(figsize=(6.4, 3.2))
        order = np.argsort(a.centre[:, 0])
        ax.plot(a.centre[order, 0], a.objective[order], ".", color="tab:blue")
        ax.set_xlabel(names[0])
        ax.set_ylabel("objective")
        ax.set_xlim(a.lower[0], a.upper[0])
        ax.set_title(title)
        return _save(fig, out_stem)
    nslice = 1 if m == 2 else (int(a.bins[2]) if a.kind == "grid" else 6)
    nslice = min(nslice, 12)
    edges = np.linspace(a.lower[2], a.upper[2], nslice + 1) if m > 2 else None
    cols = min(nslice, 4)
    rows = int(np.ceil(nslice / cols))
    fig, axes = plt.subplots(rows, cols, figsize=(3.6 * cols + 1.2, 3.2 * rows), squeeze=False,
                             layout="constrained")
    # the colour range of most elites: a few far worse ones (fallen robots, say) would
    # otherwise flatten the map; they show in the darkest colour
    vmin, vmax = (float(np.percentile(a.objective, 5)), float(a.objective.max())) \
        if a.objective.size else (0.0, 1.0)
    vmin = min(vmin, vmax - 1e-12)
    image = None
    for k, ax in enumerate(axes.ravel()):
        if k >= nslice:
            ax.axis("off")
            continue
        if edges is not None:
            top = edges[k + 1] if k < nslice - 1 else np.inf
            sel = (a.measures[:, 2] >= edges[k]) & (a.measures[:, 2] < top)
            ax.set_title(f"{names[2]} {edges[k]:.3g}..{edges[k + 1]:.3g}", fontsize=9)
        else:
            sel = np.ones(a.objective.size, bool)
        image = _panel(ax, a, sel, vmin, vmax)
        ax.set_xlabel(names[0])
        ax.set_ylabel(names[1])
    if image is not None:
        fig.colorbar(image, ax=axes.ravel().tolist(), label="objective", shrink=0.85,
                     extend="min" if a.objective.min() < vmin else "neither")
    fig.suptitle(title or f"archive: {a.objective.size} of {a.cells} cells filled")
    return _save(fig, out_stem, tight=False)  # constrained layout already


def _panel(ax, a, sel: np.ndarray, vmin: float, vmax: float):
    """One 2-D panel: a grid as an image (best elite per (x, y) bin), a CVT as coloured
    centroids (empty ones grey)."""
    lo, hi = a.lower, a.upper
    if a.kind == "grid":
        bx, by = int(a.bins[0]), int(a.bins[1])
        img = np.full((by, bx), np.nan)
        ix = np.clip(((a.centre[sel, 0] - lo[0]) / (hi[0] - lo[0]) * bx).astype(int), 0, bx - 1)
        iy = np.clip(((a.centre[sel, 1] - lo[1]) / (hi[1] - lo[1]) * by).astype(int), 0, by - 1)
        obj = a.objective[sel]
        for x, y, f in zip(ix, iy, obj, strict=True):  # the best of the hidden measures
            if not f <= img[y, x]:
                img[y, x] = f
        return ax.imshow(img, origin="lower", extent=(lo[0], hi[0], lo[1], hi[1]),
                         aspect="auto", vmin=vmin, vmax=vmax, cmap="viridis",
                         interpolation="nearest")
    ax.scatter(a.all_centres[:, 0], a.all_centres[:, 1], s=2, color="0.85", linewidths=0)
    ax.set_xlim(lo[0], hi[0])
    ax.set_ylim(lo[1], hi[1])
    return ax.scatter(a.centre[sel, 0], a.centre[sel, 1], c=a.objective[sel], s=4,
                      vmin=vmin, vmax=vmax, cmap="viridis", linewidths=0)
