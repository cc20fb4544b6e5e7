"""Robot spec values (issue 31): every number finite and within its documented physical
range, every name printable, the file read with bounds; a hostile spec is one line naming the
file, line and key, never a traceback or a simulation with MuJoCo's warnings."""

from __future__ import annotations

import json
import math
import os
import threading
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.sim.robots import build_robot, read_spec

GOOD = """[robot]
name = "nao-copy"
mjcf = "evomotion:sim/robots/nao/nao_h25.xml"
torso = "torso"
clearance_m = 0.0005

[feet]
left = "LFoot"
right = "RFoot"

[fall]
height_m = 0.2
tilt_rad = 0.7

[servo]
kp = 50.0
kv = 1.0
force = 5.0

[pose]
LKneePitch = 0.5

[evolve]
LKneePitch = [0.0, 1.5]
"""
LINES = {("robot", "clearance_m"): 5, ("fall", "height_m"): 12, ("fall", "tilt_rad"): 13,
         ("servo", "kp"): 16, ("servo", "kv"): 17, ("servo", "force"): 18,
         ("pose", "LKneePitch"): 21, ("evolve", "LKneePitch"): 24}
LINE_TEXT = {("robot", "clearance_m"): "clearance_m = 0.0005", ("fall", "height_m"):
             "height_m = 0.2", ("fall", "tilt_rad"): "tilt_rad = 0.7", ("servo", "kp"):
             "kp = 50.0", ("servo", "kv"): "kv = 1.0", ("servo", "force"): "force = 5.0",
             ("pose", "LKneePitch"): "LKneePitch = 0.5", ("evolve", "LKneePitch"):
             "LKneePitch = [0.0, 1.5]"}


def write(tmp_path: Path, text: str) -> Path:
    path = tmp_path / "r.toml"
    path.write_text(text)
    return path


def with_value(key: tuple[str, str], value: str) -> str:
    old = LINE_TEXT[key]
    name = old.split(" = ")[0]
    new = f"{name} = [{value}, 1.0]" if key[0] == "evolve" else f"{name} = {value}"
    return GOOD.replace(old, new)


@pytest.mark.parametrize("key", list(LINES))
@pytest.mark.parametrize("value", ["nan", "inf", "-inf", "1e300", "-1e300", "1" + "0" * 400,
                                   "true", '"3"'])
def test_bad_numbers_name_file_line_and_key(tmp_path, key, value):
    path = write(tmp_path, with_value(key, value))
    with pytest.raises(InputError) as e:
        read_spec(path)
    text = str(e.value)
    assert text.startswith(f"{path}:{LINES[key]}: [{key[0]}] {key[1]}: expected a "), text
    assert "\n" not in text and len(text) < 400


@pytest.mark.parametrize("key,value,fragment", [
    (("robot", "clearance_m"), "1e300", "expected a number in [0, 0.1] m, got 1e+300"),
    (("robot", "clearance_m"), "0.5", "[0, 0.1] m"),
    (("fall", "height_m"), "0", "(0, 10] m"),
    (("fall", "tilt_rad"), "4", "(0, 3.14159] rad"),
    (("servo", "kp"), "1e7", "(0, 100000] N m/rad"),
    (("servo", "kv"), "-1", "[0, 10000] N m s/rad"),
    (("servo", "force"), "0", "(0, 10000] N m"),
    (("pose", "LKneePitch"), "7", "[-6.28319, 6.28319] rad"),
    (("evolve", "LKneePitch"), "-7", "[-6.28319, 6.28319] rad"),
    (("robot", "clearance_m"), "nan", "expected a finite number (m), got nan"),
])
def test_documented_physical_ranges(tmp_path, key, value, fragment):
    with pytest.raises(InputError) as e:
        read_spec(write(tmp_path, with_value(key, value)))
    assert fragment in str(e.value), str(e.value)


def test_every_range_is_finite_and_documented():
    from evomotion.sim.robots.spec import RANGES

    doc = (Path(__file__).resolve().parents[3] / "docs" / "robots.md").read_text()
    for (section, key), (lo, hi, unit, _) in RANGES.items():
        assert math.isfinite(lo) and math.isfinite(hi) and lo < hi
        assert (key or section) in doc and unit in doc, (section, key)


def test_the_good_spec_builds_and_the_clearance_is_the_specs(tmp_path):
    robot = build_robot(read_spec(write(tmp_path, GOOD)))
    assert robot.spec.clearance_m == 0.0005 and robot.spec.servo["force"] == 5.0


@pytest.mark.parametrize("old,new,fragment", [
    ('name = "nao-copy"', 'name = "a\\nb"', "[robot] name: expected at most 64 printable"),
    ('name = "nao-copy"', f'name = "{"x" * 65}"', "at most 64 printable"),
    ('left = "LFoot"', 'left = "L\\u0000Foot"', "[feet] left: expected at most 200"),
    ('LKneePitch = 0.5', '"Knee\\r\\nerror: forged" = 0.5', "[pose] key: expected at most"),
    ('[evolve]', '["evo\\nlve"]', "unknown section [evo\\nlve]"),
    ('torso = "torso"', 'torso = ["torso"]', "[robot] torso: expected a non-empty string"),
])
def test_names_are_printable_one_line_strings(tmp_path, old, new, fragment):
    with pytest.raises(InputError) as e:
        read_spec(write(tmp_path, GOOD.replace(old, new)))
    assert fragment in str(e.value) and "\n" not in str(e.value), str(e.value)


def test_gait_kind_of_the_wrong_type_is_one_line(tmp_path):
    text = GOOD + '\n[gait]\nkind = ["biped"]\n'
    with pytest.raises(InputError, match=r"\[gait\] kind: expected one of biped, quadruped"):
        read_spec(write(tmp_path, text))


@pytest.mark.parametrize("text", ["x = " + "[" * 100_000, "x = " + "{a = " * 50_000,
                                  "x = 1" + "0" * 5000], ids=["array", "table", "integer"])
def test_deep_or_huge_toml_is_one_line(tmp_path, text):
    with pytest.raises(InputError) as e:
        read_spec(write(tmp_path, text))
    assert "not valid TOML" in str(e.value) and "\n" not in str(e.value)


def test_spec_file_size_and_kind_are_bounded(tmp_path):
    big = tmp_path / "big.toml"
    with open(big, "wb") as f:
        f.truncate(2**40)
    with pytest.raises(InputError, match="expected a robot spec of at most 1 MiB"):
        read_spec(big)
    fifo = tmp_path / "fifo.toml"
    os.mkfifo(fifo)
    out: dict = {}

    def run():
        try:
            read_spec(fifo)
        except InputError as exc:
            out["error"] = str(exc)

    t = threading.Thread(target=run, daemon=True)
    t.start()
    t.join(10)
    assert not t.is_alive() and "got a FIFO" in out.get("error", ""), out
    with pytest.raises(InputError, match="no such robot spec"):
        read_spec(tmp_path / "none.toml")


# ---- fuzz ------------------------------------------------------------------------------

def toml_value(v) -> str:
    """``v`` as TOML text (floats: nan, inf and repr; strings escaped as JSON)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, float):
        return "nan" if math.isnan(v) else ("inf" if v > 0 else "-inf") if math.isinf(v) \
            else repr(v)
    if isinstance(v, int):
        return str(v)
    if isinstance(v, str):
        return json.dumps(v)
    if isinstance(v, dict):
        return "{" + ", ".join(f"{json.dumps(k)} = {toml_value(x)}" for k, x in v.items()) + "}"
    return "[" + ", ".join(toml_value(x) for x in v) + "]"


scalars = (st.floats() | st.integers(min_value=-10**30, max_value=10**30) | st.booleans()
           | st.text(max_size=8) | st.sampled_from([1e300, -1e300, 10**400, 0.0, -0.0, 1e-320]))
values = st.recursive(scalars, lambda inner: st.lists(inner, max_size=3)
                      | st.dictionaries(st.text(max_size=4), inner, max_size=2), max_leaves=6)
KEYS = [(section, line.split(" = ")[0].strip()) for section, line in
        [("robot", "name = 1"), ("robot", "mjcf = 1"), ("robot", "torso = 1"),
         ("robot", "floor = 1"), ("robot", "keyframe = 1"), ("robot", "remove = 1"),
         ("feet", "left = 1"), ("soles", "left = 1"), ("fall", "height_m = 1"),
         ("servo", "kp = 1"), ("pose", "LKneePitch = 1"), ("evolve", "LKneePitch = 1"),
         ("gait", "kind = 1"), ("gait", "knee = 1")]]


@settings(max_examples=120, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(st.lists(st.tuples(st.sampled_from(KEYS), values), min_size=1, max_size=4))
def test_fuzz_spec_values_only_input_errors(tmp_path, changes):
    """Random values for the spec's keys: the reader (and the builder, when the reader
    accepts) raise only one-line :class:`InputError`s."""
    lines = GOOD.splitlines()
    for (section, key), value in changes:
        start = lines.index(f"[{section}]") if f"[{section}]" in lines else None
        if start is None:
            lines += ["", f"[{section}]"]
            start = len(lines) - 1
        lines.insert(start + 1, f"{key} = {toml_value(value)}")
    path = tmp_path / "fuzz.toml"
    path.write_text("\n".join(lines) + "\n")
    try:
        build_robot(read_spec(path))
    except InputError as e:
        assert "\n" not in str(e), str(e)


tomlish = st.lists(st.one_of(
    st.sampled_from(["[robot]", "[feet]", "[fall]", "[servo]", "[pose]", "[evolve]", "[gait]",
                     "[[robot]]", "[robot.x]", "", "#", "=", "[", "]", '"', "'''"]),
    st.builds(lambda k, v: f"{k} = {v}", st.sampled_from(
        ["name", "mjcf", "torso", "height_m", "kp", "left", "LKneePitch", '"a b"', "a.b",
         "kind", "x"]), values.map(toml_value)),
    st.text(max_size=20)), max_size=12).map("\n".join)


@settings(max_examples=150, deadline=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.function_scoped_fixture])
@given(tomlish)
def test_fuzz_toml_ish_text_only_input_errors(tmp_path, text):
    path = tmp_path / "fuzz.toml"
    path.write_text(text, encoding="utf-8", errors="surrogatepass")
    try:
        read_spec(path)
    except InputError as e:
        assert "\n" not in str(e), str(e)
