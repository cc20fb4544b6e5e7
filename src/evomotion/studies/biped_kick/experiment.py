"""The paper's experiment (``evomotion biped-kick study``): its Table 1, complete.

1. Each optimiser (the paper's improved CMA-ES = CMA-ES + Tent + Lévy, plain CMA-ES, the engine's
   GA with BLX-alpha) runs ``seeds`` times on the kick problem (``problem`` config: the default
   trains aims -30, -15, 0, +15, +30 deg; ``--aim 0`` straight kicks as the paper) with
   ``budget`` evaluations, through the run loop: best fitness against evaluations (median and
   interquartile band) -> ``convergence.png``, ``curves.npz``.
2. The best genome of each optimiser kicks ``kicks`` times straight (aim 0) from ball positions
   perturbed uniformly by +-``perturb_m`` in x and y; the keyframe kick (Webots ``Shoot.motion``,
   shipped) kicks from the same offsets: mean and maximum distance, execution time, fall rate,
   minimum ZMP margin (median over kicks and the worst kick).
3. Accuracy of aimed kicks (when more than one aim is trained): the same perturbed positions at
   aims -20, 0, +20 deg: median absolute angle error, share within +-10 deg, fall rate.
-> ``table.md``, ``results.json``.
"""

from __future__ import annotations

import dataclasses
from pathlib import Path
from typing import Any

import numpy as np

from evomotion.core.cmaes import CMAESConfig
from evomotion.core.ga import GAConfig
from evomotion.errors import InputError
from evomotion.run.config import Config, RunSection
from evomotion.run.in_memory import run_in_memory
from evomotion.sim.worlds import Perturbation, draw_worlds
from evomotion.studies.biped_kick.aim_table import AimTable
from evomotion.studies.biped_kick.aim_table import command as aim_command
from evomotion.studies.biped_kick.keyframe import keyframe_kicks
from evomotion.studies.biped_kick.motion import SETTLE_S, execution_time_s, named
from evomotion.studies.biped_kick.problem import KickConfig, KickProblem, against_aim


class ExperimentInterruptedError(InputError):
    """The experiment was stopped (Ctrl-C, SIGTERM) during one of its runs."""


SIGMA0 = 0.15  # the study's default (a hand-set start kick)
VARIANTS: dict[str, object] = {
    "cmaes+tent+levy": CMAESConfig(sigma0=SIGMA0, chaos=True, levy=True),
    "cmaes": CMAESConfig(sigma0=SIGMA0),
    "ga-blx": GAConfig(pop_size=20, crossover="blx_alpha"),
    "cmaes+tent": CMAESConfig(sigma0=SIGMA0, chaos=True),
    "cmaes+levy": CMAESConfig(sigma0=SIGMA0, levy=True),
}
LABELS = {"cmaes+tent+levy": "optimised: improved CMA-ES (Tent + Lévy, the paper's)",
          "cmaes": "plain CMA-ES (the default optimiser)", "ga-blx": "GA (BLX-alpha, pop 20)",
          "cmaes+tent": "CMA-ES + Tent", "cmaes+levy": "CMA-ES + Lévy"}
DEFAULT_VARIANTS = ("cmaes+tent+levy", "cmaes", "ga-blx")
ACCURACY_AIMS_DEG = (-20.0, 0.0, 20.0)


def optimise(problem: KickProblem, cfg: object, seed: int,
             budget: int) -> tuple[np.ndarray, np.ndarray, np.ndarray, float]:
    """(evaluations after each generation, best fitness so far, best genome, best fitness):
    one run in memory (:func:`~evomotion.run.in_memory.run_in_memory`) stopped after
    ``budget`` evaluations."""
    run = RunSection(seed=seed, generations=10**9, max_evaluations=budget, checkpoint_every=0)
    res = run_in_memory(Config("biped-kick", run, cfg, problem.cfg), problem)
    if res.stop_reason == "interrupted":  # Ctrl-C or SIGTERM stops the whole experiment
        raise ExperimentInterruptedError("biped-kick study: interrupted; nothing written")
    evals = np.array([r["evaluations"] for r in res.rows])
    best = np.array([r["best_so_far"] for r in res.rows])
    return evals, best, np.asarray(res.best_genome), float(res.best_fitness)


def on_grid(evals: np.ndarray, best: np.ndarray, grid: np.ndarray) -> np.ndarray:
    """Best-so-far as a step function of the evaluation count (NaN before the first)."""
    idx = np.searchsorted(evals, grid, side="right") - 1
    return np.where(idx >= 0, best[np.maximum(idx, 0)], np.nan)


def kick_worlds(problem: KickProblem, n: int, rng: np.random.Generator,
                push_ns: tuple[float, float] = (0.0, 0.0)) -> list:
    """``n`` perturbed worlds of the kick scene (:func:`evomotion.sim.worlds.draw_worlds` with
    the default ranges: friction x0.5-1.4, link masses +-10 %, torso CoM +-2 cm, motors
    +-10 %, latency 0-40 ms; no push by default: a kick is short and the check is about its
    aim; ``push_ns``: a lateral push U(lo, hi) N s at 25-75 % of the kick). The
    carpet stays calibrated: the ball's friction is set back to its nominal values in every
    world (the ball-floor contact takes the larger of the two geoms' coefficients), so the
    friction scale perturbs the robot's feet, not the ball's roll."""
    base = problem.model
    duration = float(SETTLE_S + execution_time_s(problem.kicker.start[None])[0])
    lo, hi = push_ns
    worlds = draw_worlds(base, Perturbation(push_ns=(lo, hi)), int(n), rng, duration)
    ball = base.geom("ball").id
    for w in worlds:
        w.model.geom_friction[ball] = base.geom_friction[ball]
    return worlds


def kick_draw(problem: KickProblem, n: int = 100, seeds: tuple[int, int] = (12345, 2026),
              spread_m: float = 0.02, push_ns: tuple[float, float] = (0.0, 0.0)
              ) -> tuple[np.ndarray, list]:
    """The kick checks' draw: ``n`` ball offsets ``U(+-spread_m)`` ``[n, 2]`` (m; one
    ``U(+-2 cm)`` draw from ``seeds[0]``, scaled) and ``n`` :func:`kick_worlds` from
    ``seeds[1]``, one per offset."""
    offsets = np.random.default_rng(seeds[0]).uniform(-0.02, 0.02, (n, 2)) * (spread_m / 0.02)
    return offsets, kick_worlds(problem, n, np.random.default_rng(seeds[1]), push_ns)


def perturbed_kicks(problem: KickProblem, genome: np.ndarray, offsets: np.ndarray,
                    aim_deg: float = 0.0, worlds: list | None = None,
                    adapt: bool = False, left_foot: bool = False,
                    table: AimTable | None = None) -> dict[str, np.ndarray]:
    """One kick per ball offset ``[n, 2]`` (world frame, from where the kick wants the ball
    plus the configured ``ball_dx_m``/``ball_dy_m``) at ``aim_deg`` (a single batch);
    ``worlds``: one perturbed world per kick (:func:`kick_worlds`), else the nominal scene;
    ``adapt``: the swing follows the ball's offset within the limits; ``left_foot``: the
    mirrored kick, the ball where it wants it (:meth:`.problem.KickProblem.kicks`). With the
    joint-range and motor-speed excess of the key poses as played and the share of the offset
    the swing followed. ``table``: the commanded aim chosen per kick from the ball's place
    (:func:`.aim_table.command`; with ``adapt``), the results still measured against
    ``aim_deg`` (``command_deg``: the aims commanded)."""
    if not isinstance(left_foot, bool | np.bool_):
        raise InputError(f"perturbed kicks: left_foot is one true/false, got {left_foot!r}")
    offsets = np.asarray(offsets, dtype=float)
    if offsets.ndim != 2 or offsets.shape[1] != 2:
        raise InputError(f"perturbed kicks: offsets must be [n, 2] (m), got {offsets.shape}")
    n = len(offsets)
    g = np.repeat(np.atleast_2d(genome), n, axis=0)
    aims = np.full(n, np.radians(aim_deg))
    if left_foot:  # where the left-foot kick wants the ball: the right one's, mirrored
        ball = problem.wanted_ball_xy(g, -aims) * [1.0, -1.0] + [problem.cfg.ball_dx_m,
                                                                 problem.cfg.ball_dy_m]
    else:
        ball = problem.ball_xy(g, aims)
    commanded = aims
    if table is not None:
        commanded = np.radians(aim_command(table, problem, genome, aim_deg, ball + offsets,
                                           left_foot))
    k = problem.kicks(g, commanded, ball + offsets, worlds=worlds, adapt=adapt,
                      left_foot=left_foot)
    along, lateral, error = against_aim(k["travel"], aims)  # the aim's, not the command's
    return {"distance_m": along, "lateral_m": lateral, "angle_error_deg": np.degrees(error),
            "command_deg": np.degrees(commanded), "fell": k["fell"].astype(float),
            "min_margin_m": k["min_margin_m"], "exec_time_s": k["exec_time_s"],
            "range_excess_rad": k["range_excess_rad"], "speed_excess_s": k["speed_excess_s"],
            "adapt_fraction": k["adapt_fraction"]}


def tolerant_offset(problem: KickProblem, genome: np.ndarray, aim_deg: float = 0.0,
                    max_error_deg: float = 3.0, span_m: float = 0.03,
                    step_m: float = 0.0025) -> float:
    """The lateral ball offset (m, + left of where the kick wants the ball) at the centre of
    the widest band of offsets within ``+-span_m`` where the kick at ``aim_deg`` (nominal
    world) still goes within ``max_error_deg`` of its aim: where a placement error costs least.
    A long kick's optimum puts the ball at the edge of the foot face it can hit (the default
    run's: 0.6 deg at +3 cm, 33 deg at -3 cm). 0 when no offset is within the error."""
    dy = np.arange(-span_m, span_m + step_m / 2, step_m)
    err = np.abs(perturbed_kicks(problem, genome, np.stack([np.zeros_like(dy), dy], 1),
                                 aim_deg)["angle_error_deg"])
    best, start = (0, 0), None
    for i, ok in enumerate(np.append(err <= max_error_deg, False)):
        if ok and start is None:
            start = i
        elif not ok and start is not None:
            best = max(best, (i - start, start), key=lambda b: b[0])
            start = None
    width, first = best
    return float(dy[first:first + width].mean()) if width else 0.0


def summary(m: dict[str, np.ndarray]) -> dict[str, float]:
    margin = np.asarray(m["min_margin_m"], dtype=float)
    return {"mean_distance_m": float(np.mean(m["distance_m"])),
            "max_distance_m": float(np.max(m["distance_m"])),
            "mean_abs_lateral_m": float(np.mean(np.abs(m["lateral_m"]))),
            "mean_exec_time_s": float(np.mean(m["exec_time_s"])),
            "fall_rate": float(np.mean(m["fell"])),
            "median_min_margin_m": float(np.median(margin)),
            "worst_min_margin_m": float(np.min(margin)), "n": int(len(m["fell"]))}


#: a kick whose ball travels less than this along its aim (m) is not "within ±10°"
MIN_TRAVEL_M = 0.1


def accuracy(m: dict[str, np.ndarray]) -> dict[str, float]:
    err = np.abs(m["angle_error_deg"])
    out = {"median_abs_angle_error_deg": float(np.median(err)),
           "within_10deg": float(np.mean((err <= 10.0) & (m["distance_m"] >= MIN_TRAVEL_M))),
           "fall_rate": float(np.mean(m["fell"])),
           "mean_distance_m": float(np.mean(m["distance_m"])), "n": int(len(err))}
    if "range_excess_rad" in m:  # the key poses as played, against the robot's limits
        out.update(over_limits=float(np.mean((m["range_excess_rad"] > 0)
                                             | (m["speed_excess_s"] > 0))),
                   mean_adapt_fraction=float(np.mean(m["adapt_fraction"])))
    return out


#: what :func:`run_experiment` writes in its folder
OUTPUTS = ("curves.npz", "convergence.png", "results.json", "table.md")


def study_folder(out: Path | None) -> Path:
    """The study's output folder: ``out`` (made if missing; its parent must exist: a typo in
    a path does not make folders; a folder holding files this program did not write is
    refused), else a new ``runs/biped-kick-study-<time>``."""
    from evomotion.run.folder import make_output_folder

    return make_output_folder("biped-kick-study", out)


def check_outputs(out_dir: Path) -> None:
    """Every file of :data:`OUTPUTS` can be written in ``out_dir`` (before any run)."""
    from evomotion.outfile import check_target

    for name in OUTPUTS:
        check_target(out_dir / name, f"study output {name}")


def run_experiment(out_dir: Path, seeds: int = 1, budget: int = 1500, kicks: int = 100,
                   perturb_m: float = 0.02, variants: list[str] | None = None,
                   cfg: KickConfig = KickConfig(), log=print) -> dict:
    """The experiment (see the module); its files go to the existing folder ``out_dir``."""
    import io

    from evomotion.outfile import atomic_write_bytes, atomic_write_text, write_json

    out_dir = Path(out_dir)
    check_outputs(out_dir)
    problem = KickProblem(cfg)
    names = list(variants or DEFAULT_VARIANTS)
    grid = np.arange(1, budget + 1)
    offsets = np.random.default_rng(12345).uniform(-perturb_m, perturb_m, (kicks, 2))
    curves: dict[str, np.ndarray] = {}
    rows: dict[str, dict[str, Any]] = {}
    for name in names:
        runs, best_x, best_f = [], None, -np.inf
        for seed in range(seeds):
            ev, b, x, f = optimise(problem, VARIANTS[name], seed, budget)
            runs.append(on_grid(ev, b, grid))
            log(f"{name} seed {seed}: best {f:.3f} after {ev[-1]} evaluations")
            if f > best_f:
                best_x, best_f = x, f
        if best_x is None:  # every run's best was -inf: no kick to report
            raise RuntimeError(f"biped-kick study: no {name} run found a kick")
        curves[name] = np.array(runs)
        rows[name] = {"best_fitness": best_f, "genes": named(best_x),
                      "straight": summary(perturbed_kicks(problem, best_x, offsets)),
                      "aimed": {f"{a:+.0f}": accuracy(perturbed_kicks(problem, best_x, offsets,
                                                                       a))
                                for a in (ACCURACY_AIMS_DEG if len(cfg.aims_deg) > 1 else ())}}
    buf = io.BytesIO()
    np.savez(buf, grid=grid, **curves)  # type: ignore[arg-type]  # numpy's stub: allow_pickle
    atomic_write_bytes(out_dir / "curves.npz", buf.getvalue(), "study curves")
    plot_convergence(grid, curves, out_dir / "convergence.png")
    res = {"config": dataclasses.asdict(cfg), "seeds": seeds, "budget": budget,
           "kicks": kicks, "perturb_m": perturb_m, "optimisers": rows,
           "best_fitness": max(r["best_fitness"] for r in rows.values()),
           "keyframe_kick": summary(keyframe_kicks(offsets, cfg=cfg)),
           "final_best": {k: {"median": float(np.median(v[:, -1])),
                              "q25": float(np.percentile(v[:, -1], 25)),
                              "q75": float(np.percentile(v[:, -1], 75))}
                          for k, v in curves.items()}}
    write_json(out_dir / "results.json", res, "study results")
    atomic_write_text(out_dir / "table.md", table_md(res), "study table")
    return res


def table_md(res: dict) -> str:
    head = ("| kick | mean distance (m) | max distance (m) | execution time (s) | fall rate | "
            "min ZMP margin, median / worst (mm) | kicks |")
    lines = [head, "|---|---|---|---|---|---|---|"]
    items = [(LABELS.get(k, k), r["straight"]) for k, r in res["optimisers"].items()]
    items.append(("keyframe Shoot.motion (Webots)", res["keyframe_kick"]))
    for label, s in items:
        lines.append(f"| {label} | {s['mean_distance_m']:.2f} | {s['max_distance_m']:.2f} | "
                     f"{s['mean_exec_time_s']:.2f} | {s['fall_rate']:.0%} | "
                     f"{1000 * s['median_min_margin_m']:.1f} / "
                     f"{1000 * s['worst_min_margin_m']:.1f} | {s['n']} |")
    if len(res["config"]["aims_deg"]) < 2:
        return "\n".join(lines) + "\n"
    lines += ["", "| kick | aim (deg) | median abs. angle error (deg) | within +-10 deg | "
              "fall rate | mean distance along aim (m) |", "|---|---|---|---|---|---|"]
    for k, r in res["optimisers"].items():
        for aim, a in r["aimed"].items():
            lines.append(f"| {LABELS.get(k, k)} | {aim} | {a['median_abs_angle_error_deg']:.1f} "
                         f"| {a['within_10deg']:.0%} | {a['fall_rate']:.0%} | "
                         f"{a['mean_distance_m']:.2f} |")
    return "\n".join(lines) + "\n"


def plot_convergence(grid: np.ndarray, curves: dict[str, np.ndarray], out_png: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4.5), dpi=110)
    for name, c in curves.items():
        ok = np.all(np.isfinite(c), axis=0)  # from the first generation of every run on
        if not ok.any():
            continue
        med = np.median(c[:, ok], axis=0)
        lo, hi = np.percentile(c[:, ok], 25, axis=0), np.percentile(c[:, ok], 75, axis=0)
        ax.plot(grid[ok], med, label=LABELS.get(name, name))
        ax.fill_between(grid[ok], lo, hi, alpha=0.2)
    ax.set_xlabel("evaluations")
    ax.set_ylabel("best fitness (m; below -20: no feasible kick yet)")
    ax.set_ylim(bottom=max(ax.get_ylim()[0], -3.0))
    ax.set_title("Kick optimisation: median and interquartile band over seeds")
    if ax.get_legend_handles_labels()[0]:
        ax.legend(fontsize=8)
    fig.tight_layout()
    from evomotion.outfile import save_figure

    try:
        save_figure(fig, out_png, "convergence plot")
    finally:
        plt.close(fig)
