"""Hostile MJCFs (issue 31): every file an MJCF names is read by the project with bounds,
inside the spec's folder, and every refusal is one line naming the spec and the MJCF file and
line, fast, never a MemoryError, a hang or MuJoCo simulating NaN."""

from __future__ import annotations

import os
import struct
import threading
from pathlib import Path

import pytest

from evomotion.errors import InputError
from evomotion.sim.robots import build_robot, read_spec

MAX_INCLUDE_DEPTH = 8  # evomotion.sim.robots.mjcf's documented bounds
MAX_XML_BYTES = 8 * 2**20


def mjcf_mod():
    """The MJCF reader module (imported here: the old code had none)."""
    from evomotion.sim.robots import mjcf

    return mjcf


ROBOT = """<mujoco><compiler angle="radian"/>
{head}
  <worldbody>
    <geom name="floor" type="plane" size="5 5 .1"/>
    <body name="torso" pos="0 0 .5"><freejoint/>
      <geom type="box" size=".1 .1 .1" mass="2"/>
      <body name="foot" pos="0 0 -.2"><joint name="j" type="hinge" range="-1 1"/>
        <geom name="sole" type="box" size=".05 .05 .02" mass="{mass}"/>
{body}
      </body>
    </body>
{world}
  </worldbody>
  <actuator><position joint="j" kp="20"/></actuator>
</mujoco>
"""

SPEC = """[robot]
name = "toy"
mjcf = "{mjcf}"
torso = "torso"
[feet]
only = "foot"
[fall]
height_m = 0.1
[evolve]
j = [-0.5, 0.5]
"""


def make(folder: Path, head: str = "", body: str = "", world: str = "", mass: str = "0.3",
         mjcf: str = "robot.xml") -> Path:
    """A toy robot (spec + MJCF) in ``folder``; the spec's path."""
    folder.mkdir(parents=True, exist_ok=True)
    (folder / "robot.xml").write_text(ROBOT.format(head=head, body=body, world=world,
                                                   mass=mass))
    spec = folder / "robot.toml"
    spec.write_text(SPEC.format(mjcf=mjcf))
    return spec


def refused(spec: Path, *fragments: str, seconds: float = 10.0) -> str:
    """Build ``spec`` in a thread (a blocking read must not hang the test): one line, an
    :class:`InputError` naming the spec's mjcf line and every fragment."""
    out: dict = {}

    def build():
        try:
            build_robot(read_spec(spec))
            out["built"] = True
        except BaseException as e:  # noqa: BLE001 - the test inspects it
            out["error"] = e

    t = threading.Thread(target=build, daemon=True)
    t.start()
    t.join(seconds)
    assert not t.is_alive(), "building the robot blocked"
    e = out.get("error")
    assert isinstance(e, InputError), out
    text = str(e)
    assert "\n" not in text and text.startswith(f"{spec}:3: [robot] mjcf: "), text
    for f in fragments:
        assert f in text, text
    return text


def test_the_toy_robot_builds(tmp_path):
    robot = build_robot(read_spec(make(tmp_path)))
    assert robot.joints == ("j",) and len(robot.mjcf_sha256) == 64


def include(folder: Path, name: str, content: str) -> None:
    path = folder / name
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(f"<mujoco>{content}</mujoco>\n")


def test_recursive_include_is_refused_naming_the_cycle(tmp_path):
    spec = make(tmp_path, head='<include file="a.xml"/>')
    include(tmp_path, "a.xml", '<include file="b.xml"/>')
    include(tmp_path, "b.xml", '<include file="a.xml"/>')
    refused(spec, "b.xml:1: <include file='a.xml'>",
            "includes itself (a.xml -> b.xml -> a.xml)")


def test_a_file_including_itself_and_a_file_included_twice(tmp_path):
    spec = make(tmp_path, head='<include file="a.xml"/>')
    include(tmp_path, "a.xml", '<include file="a.xml"/>')
    refused(spec, "includes itself")
    include(tmp_path, "a.xml", "")
    spec = make(tmp_path, head='<include file="a.xml"/><include file="a.xml"/>')
    refused(spec, "robot.xml:2", "already included")


def test_deep_include_chains_are_refused(tmp_path):
    spec = make(tmp_path, head='<include file="i0.xml"/>')
    for i in range(MAX_INCLUDE_DEPTH + 2):
        include(tmp_path, f"i{i}.xml", f'<include file="i{i + 1}.xml"/>')
    include(tmp_path, f"i{MAX_INCLUDE_DEPTH + 2}.xml", "")
    refused(spec, f"nested at most {MAX_INCLUDE_DEPTH} deep")


@pytest.mark.parametrize("ref,fragment", [
    ("../outside.xml", "'..' leaves it"),
    ("sub/../../outside.xml", "'..' leaves it"),
    ("/etc/hostname", "got an absolute one"),
    ("link.xml", "a link leads outside"),
])
def test_includes_stay_inside_the_spec_folder(tmp_path, ref, fragment):
    include(tmp_path, "outside.xml", "")
    robot = tmp_path / "robot"
    spec = make(robot, head=f'<include file="{ref}"/>')
    (robot / "link.xml").symlink_to(tmp_path / "outside.xml")
    refused(spec, f"robot.xml:2: <include file> {ref!r}", fragment)


def test_a_link_inside_the_folder_is_fine(tmp_path):
    include(tmp_path, "parts/a.xml", '<default><default class="x"/></default>')
    spec = make(tmp_path, head='<include file="parts.xml"/>')
    (tmp_path / "parts.xml").symlink_to(tmp_path / "parts" / "a.xml")
    build_robot(read_spec(spec))


@pytest.mark.parametrize("mjcf,fragment", [
    ("../robot.xml", "'..' leaves it"),
    ("/etc/hostname", "absolute"),
    ("evomotion:../../../etc/hostname", "'..' leaves it"),
])
def test_the_mjcf_itself_stays_inside_the_spec_folder(tmp_path, mjcf, fragment):
    spec = make(tmp_path / "r", mjcf=mjcf)
    refused(spec, fragment)


def test_huge_include_and_huge_mjcf_are_refused_by_size(tmp_path):
    spec = make(tmp_path, head='<include file="huge.xml"/>')
    with open(tmp_path / "huge.xml", "wb") as f:  # sparse: nothing written
        f.truncate(MAX_XML_BYTES + 1)
    refused(spec, "huge.xml", "expected a MJCF file of at most 8 MiB")
    (tmp_path / "robot.xml").unlink()
    with open(tmp_path / "robot.xml", "wb") as f:
        f.truncate(2**40)  # a terabyte
    refused(spec, "robot.xml", "at most 8 MiB")


def test_the_total_of_the_includes_is_bounded(tmp_path, monkeypatch):
    monkeypatch.setattr(mjcf_mod(), "MAX_XML_TOTAL", 3000)
    names = [f"p{i}.xml" for i in range(4)]
    spec = make(tmp_path, head="".join(f'<include file="{n}"/>' for n in names))
    for n in names:
        include(tmp_path, n, "<!--" + "x" * 900 + "-->")
    refused(spec, "(all MJCF files together at most 3000 bytes)")


@pytest.mark.parametrize("where", ["mjcf", "include", "mesh"])
def test_a_fifo_is_refused_without_blocking(tmp_path, where):
    spec = make(tmp_path, head={"mjcf": "", "include": '<include file="pipe.xml"/>',
                                "mesh": '<asset><mesh name="m" file="pipe.stl"/></asset>'
                                }[where])
    name = {"mjcf": "robot.xml", "include": "pipe.xml", "mesh": "pipe.stl"}[where]
    (tmp_path / name).unlink(missing_ok=True)
    os.mkfifo(tmp_path / name)
    refused(spec, name, "got a FIFO")


def test_a_device_is_refused(tmp_path):
    spec = make(tmp_path, head='<include file="zero.xml"/>')
    (tmp_path / "zero.xml").symlink_to("/dev/zero")
    refused(spec, "a link leads outside")


@pytest.mark.parametrize("text", [
    '<?xml version="1.0"?>\n<!DOCTYPE mujoco [<!ENTITY a "aaaaaaaaaa">'
    '<!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">]>\n<mujoco model="&b;"/>',
    '<!DOCTYPE mujoco SYSTEM "file:///etc/passwd">\n<mujoco/>',
])
def test_doctype_and_entities_are_refused(tmp_path, text):
    spec = make(tmp_path)
    (tmp_path / "robot.xml").write_text(text)
    refused(spec, "robot.xml:", "without <!DOCTYPE> or <!ENTITY>")


@pytest.mark.parametrize("value", ["nan", "NaN", "inf", "-inf", "1e300", "1e999"])
def test_nan_inf_and_huge_numbers_in_the_mjcf_are_refused(tmp_path, value):
    spec = make(tmp_path, mass=value)
    refused(spec, "robot.xml:8: <geom mass>", repr(value))


def test_nan_in_an_included_file_names_that_file(tmp_path):
    spec = make(tmp_path, head='<include file="opt.xml"/>')
    include(tmp_path, "opt.xml", '\n<option gravity="0 0 nan"/>')
    refused(spec, "opt.xml:2: <option gravity>", "'nan'")


@pytest.mark.parametrize("head,world,fragment", [
    ('<size memory="2G"/>', "", "data arena"),
    ('<option timestep="1e-9"/>', "", "opt.timestep = 1e-09 is outside the physical range"),
    ('<option iterations="100000000"/>', "", "<option iterations> is 100000000"),
    ('<visual><quality shadowsize="100000"/></visual>', "", "shadowsize is 100000"),
    ("", '<body pos="0 0 50000"><geom size=".1"/></body>', "body_pos = 50000"),
    ("", '<replicate count="1000"><replicate count="1000"><geom size=".1"/></replicate>'
     "</replicate>", "expected at most 1000 copies"),
    ('<asset><texture name="t" type="2d" builtin="checker" width="100000" height="100000"/>'
     "</asset>", "", "expected at most 4194304 pixels"),
    ('<size nuser_geom="100000000"/>', "", "<size nuser_geom>: expected at most 100"),
    ('<size nuserdata="1000000000"/>', "", "expected at most 1000000 nuserdata"),
    ('<asset><hfield name="h" nrow="100000" ncol="100000" size="1 1 1 1"/></asset>', "",
     "pixels"),
    ("", '<flexcomp type="grid" count="1000 1000 1" spacing=".1 .1 .1" radius=".01" '
     'name="f" dim="2"/>', "expected at most 10000 elements"),
])
def test_what_would_make_mujoco_allocate_or_loop_is_bounded(tmp_path, head, world, fragment):
    refused(make(tmp_path, head=head, world=world), fragment)


def test_deeply_nested_elements_are_refused(tmp_path):
    deep = '<body><geom size=".1"/>' * 300 + "</body>" * 300
    refused(make(tmp_path, world=deep), "nested at most 128 deep")


def test_nesting_across_included_files_is_bounded(tmp_path):
    """Each file nests 100 deep and includes the next at the bottom: no RecursionError."""
    spec = make(tmp_path, world='<include file="n0.xml"/>')
    for i in range(MAX_INCLUDE_DEPTH):
        include(tmp_path, f"n{i}.xml", "<body>" * 100 + f'<include file="n{i + 1}.xml"/>'
                + "</body>" * 100)
    include(tmp_path, f"n{MAX_INCLUDE_DEPTH}.xml", "")
    refused(spec, "nested at most 128 deep (with the included files)")


def test_many_elements_are_refused(tmp_path, monkeypatch):
    monkeypatch.setattr(mjcf_mod(), "MAX_ELEMENTS", 100)
    refused(make(tmp_path, world='<site pos="0 0 1"/>' * 200), "at most 100 elements")


def test_a_compile_error_is_one_line_naming_the_file_and_line(tmp_path):
    spec = make(tmp_path, head='<include file="parts/bad.xml"/>')
    include(tmp_path, "parts/bad.xml", '\n<worldbody>\n<geom type="box" size="1 -1 1"/>'
            "\n</worldbody>")
    text = refused(spec, "robot.xml does not compile", "must be positive in geom")
    assert f"{tmp_path / 'parts' / 'bad.xml'}:3" in text


def test_malformed_xml_names_file_line_and_column(tmp_path):
    spec = make(tmp_path)
    (tmp_path / "robot.xml").write_text("<mujoco>\n  <worldbody>\n</mujoco>\n")
    refused(spec, "robot.xml:3: column 3: expected XML (mismatched tag)")


def _stl(scale: float = 0.05) -> bytes:
    tris = [((0, 0, 0), (1, 0, 0), (0, 1, 0)), ((0, 0, 0), (0, 1, 0), (0, 0, 1)),
            ((0, 0, 0), (0, 0, 1), (1, 0, 0)), ((1, 0, 0), (0, 1, 0), (0, 0, 1))]
    out = b"\0" * 80 + struct.pack("<I", len(tris))
    for tri in tris:
        out += struct.pack("<3f", 0, 0, 0)
        for v in tri:
            out += struct.pack("<3f", *(scale * c for c in v))
        out += b"\0\0"
    return out


MESH_HEAD = '<compiler meshdir="meshes"/><asset><mesh name="toe" file="{file}"/></asset>'
MESH_BODY = '<geom type="mesh" mesh="toe" pos=".03 0 -.02" mass=".05"/>'


def test_mesh_assets_are_read_by_the_project_and_compiled_from_memory(tmp_path, monkeypatch):
    (tmp_path / "meshes" / "feet").mkdir(parents=True)
    (tmp_path / "meshes" / "feet" / "toe.stl").write_bytes(_stl())
    spec = make(tmp_path, head=MESH_HEAD.format(file="feet/toe.stl"), body=MESH_BODY)
    opened: list[str] = []
    real_from_file = __import__("mujoco").MjSpec.from_file
    monkeypatch.setattr(__import__("mujoco").MjSpec, "from_file",
                        lambda *a, **k: opened.append(a) or real_from_file(*a, **k))
    robot = build_robot(read_spec(spec))
    assert robot.model.nmesh == 1 and not opened
    assert list(robot.assets) == ["evomotion-asset-0.stl"]
    assert "<include" not in robot.xml and 'file="evomotion-asset-0.stl"' in robot.xml
    assert "meshdir" not in robot.xml


@pytest.mark.parametrize("file,fragment", [
    ("../../outside.stl", "'..' leaves it"),
    ("/etc/hostname", "absolute"),
])
def test_mesh_paths_stay_inside_the_spec_folder(tmp_path, file, fragment):
    (tmp_path / "outside.stl").write_bytes(_stl())
    spec = make(tmp_path / "r", head=MESH_HEAD.format(file=file), body=MESH_BODY)
    refused(spec, "<mesh file>", fragment)


def test_a_meshdir_outside_the_folder_is_refused(tmp_path):
    spec = make(tmp_path / "r", head='<compiler meshdir="../m"/>')
    refused(spec, "<compiler meshdir> '../m'", "'..' leaves it")


def test_a_png_texture_declaring_huge_pixels_is_refused(tmp_path):
    png = b"\x89PNG\r\n\x1a\n" + struct.pack(">I", 13) + b"IHDR" + struct.pack(
        ">II", 100_000, 100_000) + b"\x08\x02\x00\x00\x00" + b"\0" * 4
    (tmp_path / "t.png").write_bytes(png)
    spec = make(tmp_path, head='<asset><texture name="t" type="2d" file="t.png"/></asset>')
    refused(spec, "<texture file> 't.png'", "100000 x 100000")


def test_model_files_of_other_elements_are_refused(tmp_path):
    include(tmp_path, "sub.xml", "")
    spec = make(tmp_path, head='<asset><model name="s" file="sub.xml"/></asset>')
    refused(spec, "files named by <model> are not supported")


def test_robot_video_finds_its_mesh_assets(tmp_path):
    import numpy as np

    from evomotion.sim.render import RenderUnavailableError, render_video

    (tmp_path / "meshes").mkdir()
    (tmp_path / "meshes" / "toe.stl").write_bytes(_stl())
    robot = build_robot(read_spec(make(tmp_path, head=MESH_HEAD.format(file="toe.stl"),
                                       body=MESH_BODY)))
    qpos = np.tile(robot.state0[1:1 + robot.model.nq], (3, 1))
    elsewhere = tmp_path / "elsewhere"  # MuJoCo must not look for the mesh in the cwd
    elsewhere.mkdir()
    cwd = os.getcwd()
    os.chdir(elsewhere)
    try:
        out = render_video(qpos, 0.04, tmp_path / "v.mp4", width=64, height=48,
                           model_xml=robot.xml, camera="follow=torso,1.0,0.3")
    except RenderUnavailableError as exc:
        pytest.skip(f"no GL backend here: {exc}")
    finally:
        os.chdir(cwd)
    assert out.stat().st_size > 0


def test_spec_text_names_the_mjcf_in_docs():
    """The documented bounds are the code's (docs/robots.md)."""
    doc = (Path(__file__).resolve().parents[3] / "docs" / "robots.md").read_text()
    assert "MAX_XML_BYTES" not in doc  # the doc gives the numbers, not the names
    for text in ("8 MiB", "includes", "DOCTYPE", "physical range"):
        assert text in doc, text
