"""The physics keys shared by the MuJoCo studies' ``[problem]`` sections
(``sim/physics_config.py``): one validation, the worker and run-seed hooks, the key order."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import pytest

from evomotion.errors import InputError
from evomotion.sim.physics_config import (
    PerturbedWorldsConfig,
    PhysicsConfig,
    validate_physics,
)


@dataclass(frozen=True)
class OwnKeys:
    hold_s: float = 1.0


@dataclass(frozen=True)
class WithWorlds(PhysicsConfig, PerturbedWorldsConfig, OwnKeys):
    segment_s: float = 0.2  # another default, same place
    robot: str = ""


@dataclass(frozen=True)
class Physics(PhysicsConfig, OwnKeys):
    robot: str = ""


def test_keys_come_in_the_order_config_toml_lists_them():
    """The study's own keys first, then the worlds', the physics', the config's own fields; a
    redeclared field keeps its place and takes the new default."""
    assert [f.name for f in dataclasses.fields(WithWorlds)] == [
        "hold_s", "worlds", "world_seed", "world_aggregate", "world_quantile", "threads",
        "backend", "warp_device", "warp_deterministic", "warp_nconmax", "batch_rollouts",
        "segment_s", "robot"]
    assert WithWorlds().segment_s == 0.2 and PhysicsConfig().segment_s == 0.4
    assert [f.name for f in dataclasses.fields(Physics)][:2] == ["hold_s", "threads"]


def test_valid_defaults_and_the_hooks():
    validate_physics(WithWorlds())
    validate_physics(Physics())
    cfg = WithWorlds()
    assert cfg.for_worker().threads == 1 and type(cfg.for_worker()) is WithWorlds
    assert WithWorlds(threads=3).for_worker().threads == 3  # an explicit count is kept
    assert cfg.with_run_seed(7).world_seed == 7 and type(cfg.with_run_seed(7)) is WithWorlds
    assert WithWorlds(world_seed=2).with_run_seed(7).world_seed == 2


@pytest.mark.parametrize("key,value", [
    ("threads", -1), ("threads", 1025), ("backend", "gpu"), ("warp_nconmax", 0),
    ("warp_nconmax", 4097), ("batch_rollouts", 0), ("batch_rollouts", 2**20 + 1),
    ("warp_device", 0), ("warp_deterministic", 1), ("segment_s", 0.0), ("segment_s", 61.0),
    ("segment_s", float("nan")), ("worlds", 0), ("worlds", 1025), ("world_seed", -2),
    ("world_aggregate", "median"), ("world_quantile", 1.5),
])
def test_a_bad_key_is_one_line_naming_it(key, value):
    with pytest.raises(InputError) as e:
        validate_physics(WithWorlds(**{key: value}), "problem")
    assert str(e.value).startswith(f"problem.{key}:") and "\n" not in str(e.value)


def test_worlds_are_checked_only_where_the_config_has_them():
    validate_physics(Physics())  # no worlds keys: nothing to check
    with pytest.raises(InputError, match=r"^algorithm\.threads:"):
        validate_physics(Physics(threads=-1), "algorithm")
