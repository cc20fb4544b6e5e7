"""Robot folders and capabilities: every bundled robot is one folder with its spec; the NAO's
code is declared as capabilities of its spec; a copy of a spec elsewhere has none; a study
that needs a capability the robot lacks says so in one line."""

from __future__ import annotations

import shutil

import pytest

from evomotion.errors import InputError
from evomotion.sim.robots import (
    CAPABILITIES,
    ROBOTS_DIR,
    bundled_robots,
    capabilities_of,
    load_robot,
    robot_folder,
    spec_path,
)


def test_every_bundled_robot_is_one_folder_with_its_spec():
    assert bundled_robots() == ["dm-humanoid", "dm-quadruped", "nao", "op3"]
    for name in bundled_robots():
        folder = robot_folder(name)
        assert folder.parent == ROBOTS_DIR and (folder / "__init__.py").is_file()
        assert spec_path(name) == folder / f"{name}.toml"
    assert (robot_folder("nao") / "nao_h25.xml").is_file()
    assert (robot_folder("op3") / "op3.xml").is_file()


def test_the_nao_declares_its_code_and_the_others_none():
    nao = load_robot("nao")
    assert set(nao.capabilities) == set(CAPABILITIES)
    assert nao.capability("leg_ik", "x").__name__ == "evomotion.sim.robots.nao.leg_ik"
    assert capabilities_of("") == capabilities_of("nao") == nao.capabilities
    for name in ("op3",):
        assert not load_robot(name).capabilities and not capabilities_of(name)


def test_a_missing_capability_is_one_line():
    with pytest.raises(InputError, match="biped-kick needs a closed-form leg inverse "
                                         "kinematics .capability 'leg_ik'.*'op3'") as e:
        load_robot("op3").capability("leg_ik", "biped-kick")
    assert "\n" not in str(e.value)


def test_a_copy_of_the_nao_spec_has_no_code(tmp_path):
    copy = tmp_path / "my_nao.toml"
    shutil.copy(spec_path("nao"), copy)
    assert not load_robot(str(copy)).capabilities and not capabilities_of(str(copy))
    assert capabilities_of(str(tmp_path / "missing.toml")) == {}


@pytest.mark.parametrize("line, message", [
    ('leg_ik = "leg_ik"\nflying = "wings"', "unknown capability 'flying'"),
    ('leg_ik = "../evil"', "name of a module"),
])
def test_bad_capabilities_are_refused(tmp_path, line, message):
    text = spec_path("op3").read_text() + f"\n[capabilities]\n{line}\n"
    spec = tmp_path / "r.toml"
    spec.write_text(text)
    with pytest.raises(InputError, match=message):
        load_robot(str(spec))
