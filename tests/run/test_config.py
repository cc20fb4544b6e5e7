from __future__ import annotations

import pytest

from evomotion.errors import InputError
from evomotion.run.config import config_from_dict, config_to_toml, resolve_config
from evomotion.studies import get_study

S = get_study("functions")


def test_precedence_set_over_file_over_defaults(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("[run]\nseed = 5\ngenerations = 7\n[problem]\ndim = 4\n")
    cfg = resolve_config(S, f, ["run.seed=9", "algorithm.crossover_params.alpha=0.7"])
    assert cfg.run.seed == 9 and cfg.run.generations == 7 and cfg.problem.dim == 4
    assert cfg.algorithm.crossover_params == {"alpha": 0.7}
    assert cfg.algorithm.replacement == "plus"  # study default
    assert cfg.run.checkpoint_every == 10  # dataclass default


def test_round_trip_through_toml(tmp_path):
    import tomllib

    cfg = resolve_config(S, None, ["run.target=1e-3", "problem.name=ackley"])
    raw = tomllib.loads(config_to_toml(cfg))
    assert config_from_dict(S, raw) == cfg


@pytest.mark.parametrize("item,msg", [
    ("run.bogus=1", "unknown key 'run.bogus'; valid keys: address"),
    ("run.seed=abc", "run.seed: expected int"),
    ("run.generations=-3", "run.generations must be >= 0"),
    ("algorithm.pop_size=-5", "pop_size must be >= 2"),
    ("algorithm.name=nope", "unknown algorithm 'nope'"),
    ("nosection=1", "SECTION.NAME"),
    ("problem.dim", "KEY=VALUE"),
])
def test_bad_overrides(item, msg):
    with pytest.raises(InputError, match=msg):
        resolve_config(S, None, [item])


def test_malformed_toml_names_file_and_line(tmp_path):
    f = tmp_path / "bad.toml"
    f.write_text("[run]\nseed = 1\ngenerations = = 3\n")
    with pytest.raises(InputError, match=r"bad.toml:3: .*invalid TOML"):
        resolve_config(S, f)


def test_unknown_section(tmp_path):
    f = tmp_path / "c.toml"
    f.write_text("[runn]\nseed = 1\n")
    with pytest.raises(InputError, match="unknown section 'runn'"):
        resolve_config(S, f)


def test_switching_algorithm_drops_the_study_tuning_of_the_other_one():
    cfg = resolve_config(S, None, ["algorithm.name=cmaes"])
    assert cfg.algorithm.name == "cmaes"
    cfg = resolve_config(S, None, ["algorithm.name=ga"])
    assert cfg.algorithm.replacement == "plus"  # same algorithm: study tuning kept


def test_old_preset_name_resolves_to_the_paper_preset():
    """``preset="seed"`` is the old name of ``"paper"`` (issue 32) where a study has it."""
    from evomotion.run.config import current_preset_name

    arm = get_study("arm-ik")
    assert resolve_config(arm, preset="seed") == resolve_config(arm, preset="paper")
    assert resolve_config(arm, preset="seed").preset == "paper"
    assert current_preset_name(arm, "seed") == "paper"
    assert current_preset_name(arm, None) is None
    assert current_preset_name(S, "seed") == "seed"  # no paper preset: nothing to map
    with pytest.raises(InputError, match="unknown preset 'seed'"):
        resolve_config(S, preset="seed")
    raw = {"study": "arm-ik", "preset": "seed", "run": {}, "problem": {}}
    assert config_from_dict(arm, raw).preset == "seed"  # an old run's config.toml still loads


def test_a_bare_none_for_a_text_key_is_the_word():
    """``--set algorithm.restarts=none``: ``none`` reads as "no value" for optional keys
    (``run.target=none``) and as the word for a text key, where "none" is a choice."""
    cfg = resolve_config(S, None, ["algorithm.name=cmaes", "algorithm.restarts=none",
                                   "run.target=none"])
    assert cfg.algorithm.restarts == "none" and cfg.run.target is None
    with pytest.raises(InputError, match="algorithm.x0 must be one of"):
        resolve_config(S, None, ["algorithm.name=cmaes", "algorithm.x0=none"])


def test_a_preset_of_another_method_keeps_the_defaults_tuning_for_a_user_who_picks_it():
    """``humanoid-repertoire --preset map_elites --set algorithm.name=cma_me``: the study's
    CMA-ME tuning (its defaults), not CMA-ME's bare dataclass defaults."""
    rep = get_study("humanoid-repertoire")
    by_default = resolve_config(rep)
    back = resolve_config(rep, preset="map_elites", overrides=["algorithm.name=cma_me"])
    assert by_default.algorithm.name == "cma_me"
    assert back.algorithm == by_default.algorithm
    assert back.problem == resolve_config(rep, preset="map_elites").problem
