"""The gym study's defaults per environment (``Study.defaults_key = "env"``): CMA-ES on Hopper-v5
and Swimmer-v5, where it was measured best (docs/gym.md), ARS V2-t elsewhere; ``--preset
paper`` and a user who picks ARS get the paper's ARS tuning; a saved run reruns as it ran."""

from __future__ import annotations

import dataclasses
import tomllib

from evomotion.run.config import config_to_toml, resolve_config
from evomotion.studies import get_study

PAPER_ARS = {"name": "ars", "pop_size": 16, "step_size": 0.01, "noise_std": 0.025,
             "top_directions": 4}


def _alg(cfg) -> dict:
    d = dataclasses.asdict(cfg.algorithm)
    return {k: d[k] for k in PAPER_ARS} if cfg.algorithm.name == "ars" else d


def test_hopper_runs_cma_es_and_other_environments_ars():
    s = get_study("gym")
    for over in ([], ["problem.env='Hopper-v5'"], ["problem.env='Swimmer-v5'"]):  # none: Hopper
        cfg = resolve_config(s, overrides=over)
        assert cfg.algorithm.name == "cmaes"
        assert cfg.algorithm.sigma0 == 0.0005 and cfg.algorithm.x0 == "center"
        assert cfg.problem.param_bound == 100.0  # sigma 0.1 in the policy's units
    for env in ("Walker2d-v5", "HalfCheetah-v5", "Ant-v5"):
        assert _alg(resolve_config(s, overrides=[f"problem.env={env!r}"])) == PAPER_ARS


def test_picking_ars_on_hopper_gets_the_papers_tuning():
    """The study's ARS tuning is not lost under Hopper's CMA-ES: ``--preset paper`` and
    ``--set algorithm.name=ars`` both give it; the user's keys still win."""
    s = get_study("gym")
    assert _alg(resolve_config(s, preset="paper")) == PAPER_ARS
    assert _alg(resolve_config(s, overrides=["algorithm.name='ars'"])) == PAPER_ARS
    cfg = resolve_config(s, overrides=["algorithm.name='ars'", "algorithm.step_size=0.03"])
    assert cfg.algorithm.step_size == 0.03 and cfg.algorithm.top_directions == 4
    # another algorithm has no tuning here: its own defaults
    cfg = resolve_config(s, overrides=["algorithm.name='snes'"])
    assert cfg.algorithm.name == "snes" and cfg.algorithm.sigma_init == 0.1
    # the paper preset, then CMA-ES picked again; CMA-ES picked on another environment: its
    # step size in the policy's units (Study.algorithm_tunings), not 0.3 of the +-100 box
    for preset, env in (("paper", "Hopper-v5"), (None, "Walker2d-v5")):
        cfg = resolve_config(s, preset=preset, overrides=["algorithm.name='cmaes'",
                                                          f"problem.env={env!r}"])
        assert cfg.algorithm.sigma0 == 0.0005 and cfg.algorithm.x0 == "center"


def test_a_saved_ars_run_reruns_as_it_ran(tmp_path):
    """A Hopper run saved when ARS was the default has its whole ``[algorithm]``: ``--config``
    that file runs ARS with its settings, not the new default."""
    s = get_study("gym")
    old = resolve_config(s, preset="paper", overrides=["algorithm.noise_std=0.02"])
    f = tmp_path / "config.toml"
    f.write_text(config_to_toml(old))
    assert tomllib.loads(f.read_text())["algorithm"]["name"] == "ars"
    again = resolve_config(s, f)
    assert dataclasses.asdict(again.algorithm) == dataclasses.asdict(old.algorithm)
