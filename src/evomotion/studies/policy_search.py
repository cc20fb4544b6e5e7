"""Policy search on the run loop: an evolution strategy over a policy's flat parameters, with
the observation normalisation of ARS V2 (Mania et al. 2018, Algorithm 2, lines 5-8) kept in the
run's state.

Not a study: the driver the policy studies (``gym``, the NAO's balance) share. One step is one
generation: the optimizer's ``ask``, one evaluation of the population and of the distribution's
centre (the policy a user deploys) in one batch, the normaliser merged with every observation
the population saw, then ``tell``. The evaluation is the run's evaluator like any other; the
normaliser and the episode seeds travel in each row (:func:`policy_rows`), so serial, process,
Ray and Dask evaluators return the same numbers, and a resume continues bit-identically (the
state is the optimizer's plus the normaliser's arrays).

A policy problem (:class:`PolicyProblem`) evaluates rows ``[params | obs mean | obs std | seed
| episodes]``: ``episodes`` episodes starting from the seeds ``seed, seed + 1, ...``; it returns
the training fitness (e.g. the return minus ARS's survival shift) and the metrics ``return``
(the environment's own), ``steps`` and the observation moments ``obs_count``, ``obs_mean[n, o]``,
``obs_m2[n, o]`` (combined in row order, :mod:`evomotion.core.policies.normalizer`).
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, Protocol

import numpy as np

from evomotion.core.optimizer import Optimizer
from evomotion.core.policies import normalizer
from evomotion.core.policies.normalizer import Moments, RunningStats, combine, mean_std
from evomotion.core.problem import GenomeSpec, Sense
from evomotion.core.state import state_from_arrays, state_to_arrays
from evomotion.run.ask_tell import make_optimizer
from evomotion.run.contracts import OwnInitialPopulation
from evomotion.run.driver import Driver, Evaluate, StepReport
from evomotion.studies.policy_start import StartPoint, start_point

#: episode seeds are drawn below this (exact in a float64 row)
SEED_LIMIT = 2**31 - 1
EXTRA_COLUMNS = ("centre_return", "centre_steps", "train_episodes", "env_steps")


class PolicyProblem(Protocol):
    genome: GenomeSpec
    sense: Sense
    metric_names: tuple[str, ...]
    obs_dim: int
    episodes: int  # training episodes per individual
    eval_episodes: int  # episodes of the centre per generation
    normalize: bool

    def evaluate(self, rows: np.ndarray) -> Any: ...


def policy_rows(params: np.ndarray, mean: np.ndarray, std: np.ndarray, seed: int,
                episodes: int) -> np.ndarray:
    """The evaluation rows of ``params[n, P]``: each with the normaliser and its episodes."""
    n = params.shape[0]
    tail = np.concatenate([mean, std, [float(seed), float(episodes)]])
    return np.concatenate([params, np.broadcast_to(tail, (n, tail.size))], axis=1)


def neutral_rows(genomes: np.ndarray, obs_dim: int, episodes: int) -> np.ndarray:
    """``genomes`` as rows with no normalisation (mean 0, std 1) and the episodes from seed 0:
    a policy problem's ``evaluation_rows`` (:class:`evomotion.run.contracts.ContextRows`)."""
    return policy_rows(np.asarray(genomes, float), np.zeros(obs_dim), np.ones(obs_dim), 0,
                       episodes)


def split_rows(rows: np.ndarray, n_params: int, obs_dim: int
               ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Inverse of :func:`policy_rows`: ``(params, mean, std, seeds, episodes)`` per row."""
    p, o = n_params, obs_dim
    return (rows[:, :p], rows[:, p:p + o], rows[:, p + o:p + 2 * o],
            rows[:, p + 2 * o].astype(np.int64), rows[:, p + 2 * o + 1].astype(np.int64))


def normaliser(stats: RunningStats, normalize: bool) -> tuple[np.ndarray, np.ndarray]:
    """The normaliser a generation evaluates with: the running mean and std
    (:func:`evomotion.core.policies.normalizer.mean_std`), or the identity with normalisation
    off (ARS V1)."""
    if not normalize:
        return np.zeros(stats.obs_dim), np.ones(stats.obs_dim)
    return mean_std(stats)


def valid_moments(ev_metrics: dict[str, np.ndarray], n: int) -> Moments | None:
    """The observation moments of the first ``n`` rows taken together (rows in order; a failed
    row, with non-finite moments, left out); ``None`` when the problem gave none."""
    if not {"obs_count", "obs_mean", "obs_m2"} <= set(ev_metrics):
        return None
    counts = np.asarray(ev_metrics["obs_count"][:n], float)
    means, m2s = ev_metrics["obs_mean"][:n], ev_metrics["obs_m2"][:n]
    ok = np.isfinite(counts) & np.isfinite(means).all(axis=1) & np.isfinite(m2s).all(axis=1)
    return combine(np.where(ok, counts, 0).astype(np.int64), np.where(ok[:, None], means, 0.0),
                   np.where(ok[:, None], m2s, 0.0))


@dataclass(frozen=True)
class PolicySearchState:
    opt: Any
    obs: RunningStats  # every observation of the training episodes so far (ARS V2)
    best_x: np.ndarray  # the centre with the best evaluated return so far
    best_cost: float  # minus that return
    best_obs_mean: np.ndarray  # the normaliser it was evaluated with
    best_obs_std: np.ndarray
    train_episodes: int = 0
    env_steps: int = 0


class PolicySearchDriver(Driver):
    """An ES optimizer over ``problem``'s policy parameters (sense: maximise the return)."""

    sense: Sense = "max"
    extra_columns = EXTRA_COLUMNS

    def __init__(self, problem: PolicyProblem, optimizer: Optimizer,
                 start_policy: str = "") -> None:
        self.problem, self.opt, self.start_policy = problem, optimizer, start_policy
        self._start: StartPoint | None = None

    def check_new_run(self) -> None:
        """Read and check ``problem.start_policy`` (a resume never reads it)."""
        self._start = start_point(self.problem, self.start_policy)

    def init(self, rng: np.random.Generator) -> PolicySearchState:
        o = self.problem.obs_dim
        p = self.problem  # a problem with its own start (a fitted gait tape): as AskTellDriver
        if self.start_policy and self._start is None:
            self.check_new_run()
        if self._start is not None:  # an exported policy (problem.start_policy, policy_start.py)
            opt_state, obs = self.opt.init(rng, self._start.genome[None]), self._start.obs
        else:
            opt_state = (self.opt.init(rng, p.initial_population(1, rng))
                         if isinstance(p, OwnInitialPopulation) else self.opt.init(rng))
            obs = normalizer.init(o)
        return PolicySearchState(opt_state, obs,
                                 np.asarray(self.opt.center(opt_state), float).copy(),
                                 float("inf"), np.zeros(o), np.ones(o))

    def step(self, state: PolicySearchState, rng: np.random.Generator,
             evaluate: Evaluate) -> tuple[PolicySearchState, StepReport]:
        p = self.problem
        genomes, opt_state = self.opt.ask(state.opt, rng)
        centre = np.asarray(self.opt.center(opt_state), float)[None]
        mean, std = normaliser(state.obs, p.normalize)
        train_seed, eval_seed = (int(s) for s in rng.integers(0, SEED_LIMIT, size=2))
        rows = np.concatenate([policy_rows(genomes, mean, std, train_seed, p.episodes),
                               policy_rows(centre, mean, std, eval_seed, p.eval_episodes)])
        ev = evaluate(rows)
        n = len(genomes)
        cost = -np.asarray(ev.fitness[:n], float)
        opt_state = self.opt.tell(opt_state, genomes, cost, rng)
        batch = valid_moments(ev.metrics, n)
        obs = state.obs if batch is None else normalizer.merge(state.obs, batch)
        ret = float(ev.metrics["return"][n]) if "return" in ev.metrics else float("nan")
        steps = ev.metrics.get("steps", np.zeros(n + 1))
        new = dataclasses.replace(
            state, opt=opt_state, obs=obs,
            train_episodes=state.train_episodes + n * p.episodes,
            env_steps=state.env_steps + int(np.nansum(steps[:n]) * p.episodes
                                            + steps[n] * p.eval_episodes))
        best_metrics = None
        if np.isfinite(ret) and -ret < state.best_cost:
            new = dataclasses.replace(new, best_x=centre[0].copy(), best_cost=-ret,
                                      best_obs_mean=mean, best_obs_std=std)
            best_metrics = {"return": ret, "steps": float(steps[n])}
        failed = ev.failed_mask()
        extras = {"centre_return": ret, "centre_steps": float(steps[n]),
                  "train_episodes": new.train_episodes, "env_steps": new.env_steps}
        return new, StepReport(len(rows), cost, genomes, int(failed.sum()), list(ev.errors),
                               best_metrics, extras)

    def best(self, state: PolicySearchState) -> tuple[np.ndarray, float]:
        return state.best_x, float(state.best_cost)

    def stop(self, state: PolicySearchState) -> str | None:
        return self.opt.stop(state.opt)

    def state_type(self) -> type:
        return PolicySearchState

    def state_arrays(self, state: PolicySearchState
                     ) -> tuple[dict[str, np.ndarray], dict[str, Any]]:
        arrays, meta = state_to_arrays(state)
        return {k: np.array(v, copy=True) for k, v in arrays.items()}, meta

    def restore(self, arrays: dict[str, np.ndarray], meta: dict[str, Any]) -> PolicySearchState:
        opt_type = type(self.opt.init(np.random.default_rng(0)))
        opt_state = state_from_arrays(opt_type, arrays, meta, "opt.")
        obs = state_from_arrays(RunningStats, arrays, meta, "obs.")
        fields: dict[str, Any] = {
            f.name: (np.array(arrays[f.name]) if f.name in arrays else meta[f.name])
            for f in dataclasses.fields(PolicySearchState) if f.name not in ("opt", "obs")}
        return PolicySearchState(opt=opt_state, obs=obs, **fields)

    def check_state(self, state: PolicySearchState) -> None:
        o, d = self.problem.obs_dim, self.problem.genome.dim
        if np.shape(state.obs.mean) != (o,) or np.shape(state.obs.m2) != (o,):
            raise ValueError(f"normaliser of {np.shape(state.obs.mean)}, expected ({o},)")
        if np.shape(state.best_x) != (d,):
            raise ValueError(f"best policy of {np.shape(state.best_x)}, expected ({d},)")


def make_policy_driver(problem: PolicyProblem, config: Any) -> PolicySearchDriver:
    """The study factory: the registered optimizer ``algorithm.name`` on the policy, started
    where ``problem.start_policy`` says (:mod:`evomotion.studies.policy_start`) if it is set:
    read when a new run is checked (:meth:`PolicySearchDriver.check_new_run`) or started."""
    return PolicySearchDriver(problem, make_optimizer(problem, config.algorithm),
                              getattr(config.problem, "start_policy", ""))


def observation_moments(count: np.ndarray, sums: np.ndarray, sumsqs: np.ndarray
                        ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per episode ``(count, mean[o], m2[o])`` (Welford's moments, for :class:`EpisodeRows`)
    from a closed-loop run's observation count, sums and sums of squares."""
    n = np.asarray(count).astype(np.int64)
    mean = sums / np.maximum(n, 1)[:, None]
    return n, mean, np.maximum(sumsqs - n[:, None] * mean ** 2, 0.0)


#: the optimizers a policy search runs (core/es and CMA-ES), each through the policy driver
POLICY_OPTIMIZERS = ("ars", "openai_es", "pgpe", "snes", "cmaes")


def policy_algorithms() -> dict:
    """A policy study's ``algorithms``: ``{name: (config class, make_policy_driver)}``."""
    from evomotion.core.algorithms import ALGORITHMS

    return {name: (ALGORITHMS[name][0], make_policy_driver) for name in POLICY_OPTIMIZERS}


def best_record(ctx: Any) -> dict[str, Any]:
    """A policy study's ``best.json`` extras: the best centre's return, episodes, steps."""
    s = ctx.state
    if s is None:
        return {}
    return {"centre_return": -float(s.best_cost) if s.best_cost < float("inf") else None,
            "train_episodes": int(s.train_episodes), "env_steps": int(s.env_steps)}


@dataclass(frozen=True)
class EpisodeRows:
    """The episodes of evaluation rows: ``owner[e]`` (the row of episode ``e``) and its seed
    ``seeds[e]`` (a row's episodes start from ``seed, seed + 1, ...``)."""

    owner: np.ndarray
    seeds: np.ndarray
    n_rows: int

    @classmethod
    def of(cls, seeds: np.ndarray, episodes: np.ndarray, max_episodes: int) -> EpisodeRows:
        if (episodes < 1).any() or (episodes > max_episodes).any():
            raise ValueError("episodes per row out of range")
        owner = np.repeat(np.arange(len(seeds)), episodes)
        start = np.repeat(np.cumsum(episodes) - episodes, episodes)
        return cls(owner, np.repeat(seeds, episodes) + (np.arange(owner.size) - start),
                   len(seeds))

    def mean(self, values: np.ndarray) -> np.ndarray:
        """The mean over each row's episodes of per-episode ``values``."""
        per = np.bincount(self.owner, minlength=self.n_rows).astype(float)
        return np.bincount(self.owner, np.asarray(values, float), minlength=self.n_rows) / per

    def moments(self, counts: np.ndarray, means: np.ndarray, m2s: np.ndarray
                ) -> dict[str, np.ndarray]:
        """The metrics ``obs_count``, ``obs_mean``, ``obs_m2`` per row: its episodes'
        observation moments taken together in order."""
        n, o = self.n_rows, means.shape[1]
        out_c, out_m, out_s = np.zeros(n), np.zeros((n, o)), np.zeros((n, o))
        for r in range(n):  # usually one or two episodes per row
            sel = self.owner == r
            c, m, s = combine(np.asarray(counts[sel]).astype(np.int64), means[sel], m2s[sel])
            out_c[r], out_m[r], out_s[r] = float(c), m, s
        return {"obs_count": out_c, "obs_mean": out_m, "obs_m2": out_s}


def write_policy_files(ctx: Any, extra: dict[str, Any] | None = None) -> None:
    """``policy.npz``/``.py``/``.onnx`` of the run's best centre so far (the problem's
    ``policy`` spec, the normaliser it was evaluated with), and ``extra``'s JSON files
    (``{name: record}``); ``policy.onnx`` is skipped with one note without the ``onnx``
    extra. A study's checkpoint hook."""
    import json
    from pathlib import Path

    from evomotion.core.policies.export import export_policy
    from evomotion.outfile import atomic_write_text

    state, problem = ctx.state, ctx.problem
    if state is None or problem is None or ctx.out_dir is None or \
            not state.best_cost < float("inf"):
        return
    formats: tuple[str, ...] = ("npz", "py", "onnx")
    try:
        import onnx  # noqa: F401
    except ImportError:
        formats = ("npz", "py")
        if not ctx.cache.get("onnx_note"):
            ctx.log("note: policy.onnx not written (pip install 'evomotion[onnx]')")
            ctx.cache["onnx_note"] = True
    # a problem that searches other numbers than the policy's (a symmetric controller's)
    # maps them: ``policy_params(genomes)``
    params = problem.policy_params(state.best_x) if hasattr(problem, "policy_params") \
        else state.best_x
    export_policy(ctx.out_dir, problem.policy, params, state.best_obs_mean,
                  state.best_obs_std, formats)
    for name, record in (extra or {}).items():
        atomic_write_text(Path(ctx.out_dir) / name, json.dumps(record, indent=1) + "\n")


def log_best_centre(ctx: Any, study: str, also: tuple[str, ...] = ()) -> None:
    """The closing log line of a robot's policy study (humanoid-balance, humanoid-walk): the
    best centre's score and the files written (``also``: the study's own, where present)."""
    s = ctx.state
    if s is not None and s.best_cost < float("inf"):
        ctx.log(f"{study}: best centre score {-s.best_cost:.3f} after "
                f"{s.train_episodes} training episodes; policy.npz, policy.py, policy.json"
                + (", policy.onnx" if not ctx.cache.get("onnx_note") else "")
                + "".join(f", {f}" for f in also
                          if ctx.out_dir is not None and (ctx.out_dir / f).is_file())
                + f"; evomotion {study} compare RUN measures it")
