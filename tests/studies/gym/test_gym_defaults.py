"""The gym study's defaults per environment (``Study.defaults_key = "env"``): CMA-ES on Hopper-v5
and Swimmer-v5, where it was measured best (docs/gym.md), ARS V2-t with the paper's setting
of the task elsewhere; ``--preset paper`` is the paper's setting of each task
(``Study.robot_presets``); a user who picks ARS gets an ARS tuning; a saved run reruns as it
ran."""

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
    # the paper's hyperparameters of the task where it ran ARS (measured best there)
    for env, n, b in (("HalfCheetah-v5", 32, 4), ("Walker2d-v5", 40, 30), ("Ant-v5", 60, 20),
                      ("Humanoid-v5", 230, 230)):
        cfg = resolve_config(s, overrides=[f"problem.env={env!r}"])
        assert cfg.algorithm.name == "ars" and cfg.problem.normalize, env
        assert (cfg.algorithm.pop_size, cfg.algorithm.top_directions) == (2 * n, b), env
    # an environment the paper did not run: its Hopper setting
    cfg = resolve_config(s, overrides=["problem.env='InvertedPendulum-v5'"])
    assert _alg(cfg) == PAPER_ARS


def test_the_paper_preset_is_the_papers_setting_of_each_task():
    """``--preset paper``: Mania et al. 2018's hyperparameters of the task (alpha, N, b, nu;
    V1-t without normalisation on Swimmer), Hopper's on another environment; a user's key
    still wins."""
    s = get_study("gym")
    paper = {"Swimmer-v5": (0.02, 1, 1, 0.01, False), "Hopper-v5": (0.01, 8, 4, 0.025, True),
             "HalfCheetah-v5": (0.02, 32, 4, 0.03, True),
             "Walker2d-v5": (0.03, 40, 30, 0.025, True),
             "Ant-v5": (0.015, 60, 20, 0.025, True),
             "Humanoid-v5": (0.02, 230, 230, 0.0075, True)}
    for env, (alpha, n, b, nu, norm) in paper.items():
        cfg = resolve_config(s, preset="paper", overrides=[f"problem.env={env!r}"])
        a = cfg.algorithm
        assert (a.name, a.step_size, a.pop_size, a.top_directions, a.noise_std,
                cfg.problem.normalize) == ("ars", alpha, 2 * n, b, nu, norm), env
    assert _alg(resolve_config(s, preset="paper", overrides=["problem.env='Pusher-v5'"])) \
        == PAPER_ARS
    cfg = resolve_config(s, preset="paper", overrides=["problem.env='Swimmer-v5'",
                                                       "problem.normalize=true",
                                                       "algorithm.pop_size=8"])
    assert cfg.problem.normalize and cfg.algorithm.pop_size == 8
    assert cfg.algorithm.step_size == 0.02


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


def test_another_version_of_a_task_gets_its_settings():
    """The settings are per task (``Study.defaults_alias``): ``Walker2d-v4`` gets Walker2d's
    defaults and paper setting, ``Swimmer-v4`` Swimmer's, Hopper's other versions its CMA-ES;
    an unknown task or a malformed id keeps its own (Hopper's ARS setting)."""
    from evomotion.studies.gym.study import v5_id

    s = get_study("gym")
    for env in ("Walker2d-v4", "Walker2d-v5"):
        cfg = resolve_config(s, overrides=[f"problem.env={env!r}"])
        assert (cfg.algorithm.name, cfg.algorithm.pop_size, cfg.algorithm.top_directions) \
            == ("ars", 80, 30), env
        assert cfg.problem.env == env
    cfg = resolve_config(s, preset="paper", overrides=["problem.env='Swimmer-v4'"])
    assert (cfg.algorithm.pop_size, cfg.problem.normalize) == (2, False)
    assert resolve_config(s, overrides=["problem.env='Hopper-v4'"]).algorithm.name == "cmaes"
    for env in ("Walker2d-vX", "Walker2d", "Walker2d-v", "Walker3d-v4", "walker2d-v4"):
        assert v5_id(env) == env
        assert _alg(resolve_config(s, overrides=[f"problem.env={env!r}"])) == PAPER_ARS, env
    assert v5_id("Ant-v4") == v5_id("Ant-v12") == "Ant-v5"
    from evomotion.run.config import default_algorithm

    assert default_algorithm(s, "Swimmer-v4") == "cmaes"
    assert default_algorithm(s, "HalfCheetah-v4") == default_algorithm(s, "Pusher-v4") == "ars"
