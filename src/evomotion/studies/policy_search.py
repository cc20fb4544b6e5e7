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
from evomotion.core.state import checked_fields, state_from_arrays, state_to_arrays
from evomotion.run.ask_tell import make_optimizer
from evomotion.run.contracts import OwnInitialPopulation
from evomotion.run.driver import Driver, Evaluate, StepReport
from evomotion.studies.policy_start import StartPoint, start_point
from evomotion.studies.policy_validation import (
    Validated,
    due,
    no_validated,
    validation_cost,
    validation_seeds,
)

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


def policy_rows(params: np.ndarray, mean: np.ndarray, std: np.ndarray,
                seed: int | np.ndarray, episodes: int) -> np.ndarray:
    """The evaluation rows of ``params[n, P]``: each with the normaliser and its episodes
    (from ``seed``, one for every row or ``seed[n]``)."""
    n = params.shape[0]
    tail = np.concatenate([mean, std, [0.0, float(episodes)]])
    rows = np.concatenate([params, np.broadcast_to(tail, (n, tail.size))], axis=1)
    rows[:, -2] = np.asarray(seed, dtype=np.int64).astype(float)
    return rows


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
    generation: int = 0  # generations stepped (the validation schedule counts them)
    #: the best centre on the validation episodes (policy_validation.py; unused when off)
    valid: Validated | None = None


def chosen_validated(state: PolicySearchState) -> Validated | None:
    """The best validated centre where validation has chosen one (a finite validation
    cost), else None."""
    v = state.valid
    return v if v is not None and v.cost < float("inf") else None


def exported(state: PolicySearchState) -> tuple[np.ndarray, float, np.ndarray, np.ndarray]:
    """``(x, cost, obs mean, obs std)`` of the centre a run exports and reports as its best:
    the best validated one where validation has chosen one, else the best evaluated."""
    v = chosen_validated(state)
    if v is not None:
        return v.x, v.cost, v.obs_mean, v.obs_std
    return state.best_x, state.best_cost, state.best_obs_mean, state.best_obs_std


class PolicySearchDriver(Driver):
    """An ES optimizer over ``problem``'s policy parameters (sense: maximise the return)."""

    sense: Sense = "max"
    extra_columns: tuple[str, ...] = EXTRA_COLUMNS

    def __init__(self, problem: PolicyProblem, optimizer: Optimizer,
                 start_policy: str = "", validate_every: int = 0,
                 validate_episodes: int = 32) -> None:
        self.problem, self.opt, self.start_policy = problem, optimizer, start_policy
        self.validate_every, self.validate_episodes = validate_every, validate_episodes
        if validate_every > 0:  # the validated centre's mean return, NaN between validations
            self.extra_columns = EXTRA_COLUMNS + ("valid_return",)
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
        x0 = np.asarray(self.opt.center(opt_state), float).copy()
        return PolicySearchState(opt_state, obs, x0, float("inf"), np.zeros(o), np.ones(o),
                                 valid=no_validated(x0, o) if self.validate_every else None)

    def step(self, state: PolicySearchState, rng: np.random.Generator,
             evaluate: Evaluate) -> tuple[PolicySearchState, StepReport]:
        p = self.problem
        genomes, opt_state = self.opt.ask(state.opt, rng)
        centre = np.asarray(self.opt.center(opt_state), float)[None]
        mean, std = normaliser(state.obs, p.normalize)
        train_seed, eval_seed = (int(s) for s in rng.integers(0, SEED_LIMIT, size=2))
        v = self.validate_episodes if due(state.generation, self.validate_every) else 0
        rows = np.concatenate([policy_rows(genomes, mean, std, train_seed, p.episodes),
                               policy_rows(centre, mean, std, eval_seed, p.eval_episodes),
                               policy_rows(np.repeat(centre, v, axis=0), mean, std,
                                           validation_seeds(v), 1)])
        ev = evaluate(rows)
        n = len(genomes)
        cost = -np.asarray(ev.fitness[:n], float)
        opt_state = self.opt.tell(opt_state, genomes, cost, rng)
        batch = valid_moments(ev.metrics, n)
        obs = state.obs if batch is None else normalizer.merge(state.obs, batch)
        ret = float(ev.metrics["return"][n]) if "return" in ev.metrics else float("nan")
        steps = ev.metrics.get("steps", np.zeros(len(rows)))
        new = dataclasses.replace(
            state, opt=opt_state, obs=obs, generation=state.generation + 1,
            train_episodes=state.train_episodes + n * p.episodes,
            env_steps=state.env_steps + int(np.nansum(steps[:n]) * p.episodes
                                            + steps[n] * p.eval_episodes
                                            + np.nansum(steps[n + 1:])))
        best_metrics = None
        if np.isfinite(ret) and -ret < state.best_cost:
            new = dataclasses.replace(new, best_x=centre[0].copy(), best_cost=-ret,
                                      best_obs_mean=mean, best_obs_std=std)
            best_metrics = {"return": ret, "steps": float(steps[n])}
        extras = {"centre_return": ret, "centre_steps": float(steps[n]),
                  "train_episodes": new.train_episodes, "env_steps": new.env_steps}
        if self.validate_every:
            new, best_metrics, extras = self._validated(new, state, ev, n, v > 0, centre[0],
                                                        mean, std, extras)
        failed = ev.failed_mask()
        return new, StepReport(len(rows), cost, genomes, int(failed.sum()), list(ev.errors),
                               best_metrics, extras)

    def _validated(self, new: PolicySearchState, state: PolicySearchState, ev: Any, n: int,
                   validated: bool, centre: np.ndarray, mean: np.ndarray, std: np.ndarray,
                   extras: dict[str, Any]) -> tuple:
        """With validation on: the state, best metrics and extras after this generation's
        validation rows (rows ``n + 1 ...``, where ``validated``; none between validations)."""
        valid = state.valid or no_validated(state.best_x, len(mean))
        best_metrics, extras = None, {**extras, "valid_return": float("nan")}
        if validated:
            returns = np.asarray(ev.metrics["return"][n + 1:], float) \
                if "return" in ev.metrics else np.full(1, np.nan)
            cost = validation_cost(returns)
            extras["valid_return"] = -cost if cost < float("inf") else float("nan")
            if cost < valid.cost:
                valid = Validated(centre.copy(), cost, mean, std, state.generation)
                best_metrics = {"return": -cost, "episodes": float(len(returns)),
                                "generation": float(state.generation)}
        return dataclasses.replace(new, valid=valid), best_metrics, extras

    def best(self, state: PolicySearchState) -> tuple[np.ndarray, float]:
        x, cost, _, _ = exported(state)
        return x, float(cost)

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
        later = ("generation", "valid")  # absent from checkpoints of before validation
        fields: dict[str, Any] = {
            f.name: (np.array(arrays[f.name]) if f.name in arrays else meta[f.name])
            for f in dataclasses.fields(PolicySearchState)
            if f.name not in ("opt", "obs", "valid")
            and (f.name not in later or f.name in arrays or f.name in meta)}
        valid = state_from_arrays(Validated, arrays, meta, "valid.") \
            if "valid.x" in arrays else None
        return PolicySearchState(opt=opt_state, obs=obs, valid=valid,
                                 **checked_fields(PolicySearchState, fields))

    def check_state(self, state: PolicySearchState) -> None:
        o, d = self.problem.obs_dim, self.problem.genome.dim
        if np.shape(state.obs.mean) != (o,) or np.shape(state.obs.m2) != (o,):
            raise ValueError(f"normaliser mean of {np.shape(state.obs.mean)} and M2 of "
                             f"{np.shape(state.obs.m2)}, expected ({o},)")
        if np.shape(state.best_x) != (d,) or np.shape(state.best_obs_mean) != (o,) \
                or np.shape(state.best_obs_std) != (o,):
            raise ValueError(f"best policy of {np.shape(state.best_x)} with a normaliser of "
                             f"{np.shape(state.best_obs_mean)}, expected ({d},) and ({o},)")
        v = state.valid
        if v is not None and (np.shape(v.x) != (d,) or np.shape(v.obs_mean) != (o,)
                              or np.shape(v.obs_std) != (o,)):
            raise ValueError(f"validated policy of {np.shape(v.x)} with a normaliser of "
                             f"{np.shape(v.obs_mean)}, expected ({d},) and ({o},)")
        finite = [state.obs.mean, state.obs.m2, state.best_x, state.best_obs_mean,
                  state.best_obs_std]
        if v is not None:
            finite += [v.x, v.obs_mean, v.obs_std]
        if not all(np.isfinite(a).all() for a in finite) or np.any(state.obs.m2 < 0) \
                or np.any(np.asarray(state.obs.count) < 0):
            raise ValueError("a policy or normaliser with non-finite or negative moments")
        self.opt.check_next_step(state.opt)


def make_policy_driver(problem: PolicyProblem, config: Any) -> PolicySearchDriver:
    """The study factory: the registered optimizer ``algorithm.name`` on the policy, started
    where ``problem.start_policy`` says (:mod:`evomotion.studies.policy_start`) if it is set:
    read when a new run is checked (:meth:`PolicySearchDriver.check_new_run`) or started."""
    return PolicySearchDriver(problem, make_optimizer(problem, config.algorithm),
                              getattr(config.problem, "start_policy", ""),
                              getattr(config.problem, "validate_every", 0),
                              getattr(config.problem, "validate_episodes", 32))


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
