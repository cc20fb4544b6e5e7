"""Fuzzing every file reader: property-based (hypothesis) inputs from each format's grammar and
mutations of the valid bundled / fixture files (bit flips, deletions, duplicated and swapped
lines, truncation, inserted NaN / inf / huge numbers, NULs, CRs and non-UTF-8 bytes).

The only exception that may escape a reader is the project's FileFormatError (InputError for a
map's blocked or cut-off endpoints), as one line naming the file; whatever is accepted is valid
(finite numbers, consistent shapes, see ``fuzz_readers``). Inputs per run: READERS x
(MUTATION_EXAMPLES + PROPERTY_EXAMPLES) = 6 x (1,000 + 600) = 9,600 (derandomized, no
database; the seed files once more each), printed at the end of the module (``pytest -s``).
"""

from __future__ import annotations

import json
import os
from collections import Counter

import pytest
from fuzz_readers import READERS, accepts_or_one_line_error, seeds
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from evomotion.sim.motion import NAO_JOINT_NAMES

#: EVOMOTION_FUZZ_SCALE=N multiplies the counts and draws fresh random inputs (a longer hunt);
#: the default run is derandomized (the same inputs every run).
SCALE = int(os.environ.get("EVOMOTION_FUZZ_SCALE", "1"))
MUTATION_EXAMPLES = 1000 * SCALE  # per reader
PROPERTY_EXAMPLES = 600 * SCALE  # per reader
FUZZ = dict(deadline=None, database=None, derandomize=SCALE == 1,
            suppress_health_check=[HealthCheck.function_scoped_fixture, HealthCheck.too_slow])
SUFFIX = {"motion": ".motion", "scenario": ".scen", "movingai": ".map", "binary": ".txt",
          "plan": ".json", "world": ".world"}
SEEDS = {r: [p.read_bytes() for p in seeds(r)] for r in READERS}
TOKENS = [b"nan", b"NaN", b"inf", b"-inf", b"Infinity", b"1e999", b"-1e400", b"99999999999",
          b"9" * 40, b"0", b"-1", b"1.5", b"*", b"\xff", b"\xc3", b"\xed\xa0\x80", b"\x00",
          b"\r", b"\n", b"\n\n", b",", b" ", b"\t", b"null", b"true", b"[", b"{", b"\"abc\"",
          b"map", b"type octile", b"height 0", b"width 99999999", b"#", b"@", b".", b"2",
          b"\xef\xbb\xbf", b"\xc3\xa9", "\u0661".encode()]


OUTCOMES: Counter = Counter()  # (reader, "ok" | "error") over the run: see the fuzz report


def _run(reader: str, tmp_path, data: bytes) -> str:
    path = tmp_path / f"input{SUFFIX[reader]}"
    path.write_bytes(data)
    out = accepts_or_one_line_error(reader, path)
    OUTCOMES[reader, "ok" if out == "ok" else "error"] += 1
    return out


def teardown_module() -> None:
    print("\nfuzz inputs per reader:", {r: OUTCOMES[r, "ok"] + OUTCOMES[r, "error"]
                                         for r in sorted(READERS)},
          "accepted:", {r: OUTCOMES[r, "ok"] for r in sorted(READERS)})


@st.composite
def mutated(draw, reader: str) -> bytes:
    data = bytearray(draw(st.sampled_from(SEEDS[reader])))
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["flip", "delete", "dup", "swap", "truncate", "insert",
                                   "replace_number"]))
        n = len(data)
        i = draw(st.integers(0, max(n - 1, 0)))
        if op == "flip" and n:
            data[i] ^= 1 << draw(st.integers(0, 7))
        elif op == "delete":
            del data[i:i + draw(st.integers(1, 64))]
        elif op in ("dup", "swap"):
            lines = bytes(data).split(b"\n")
            a = draw(st.integers(0, len(lines) - 1))
            b = draw(st.integers(0, len(lines) - 1))
            if op == "dup":
                lines.insert(a, lines[b])
            else:
                lines[a], lines[b] = lines[b], lines[a]
            data = bytearray(b"\n".join(lines))
        elif op == "truncate":
            del data[i:]
        elif op == "insert":
            data[i:i] = draw(st.sampled_from(TOKENS))
        else:  # replace the number (or word) that starts near i
            j = i
            while j < n and data[j:j + 1] not in b" ,\n\t[]{}:":
                j += 1
            data[i:j] = draw(st.sampled_from(TOKENS))
    return bytes(data)


@pytest.mark.parametrize("reader", sorted(READERS))
def test_seed_files_are_accepted(reader, tmp_path):
    assert SEEDS[reader]
    for data in SEEDS[reader]:
        assert _run(reader, tmp_path, data) == "ok"


@pytest.mark.parametrize("reader", sorted(READERS))
def test_mutated_files(reader, tmp_path):
    @settings(max_examples=MUTATION_EXAMPLES, **FUZZ)
    @given(mutated(reader))
    def check(data):
        _run(reader, tmp_path, data)

    check()


# -- property-based inputs from each format's grammar -------------------------------------
finite = st.floats(allow_nan=False, allow_infinity=False, width=64)
any_float = st.floats(allow_nan=True, allow_infinity=True)
number_text = st.one_of(finite.map(repr), any_float.map(repr), st.integers(-10**12, 10**12)
                        .map(str), st.sampled_from(["nan", "inf", "1e999", "*", "1_0", "+-1",
                                                    "", "x", "\u00b2", "9" * 30]))
junk = st.text(alphabet=st.characters(codec="utf-8"), max_size=8)


@st.composite
def motion_text(draw) -> bytes:
    joints = draw(st.lists(st.sampled_from(sorted(NAO_JOINT_NAMES) + ["LTail", ""]),
                           min_size=0, max_size=5))
    head = draw(st.sampled_from(["#WEBOTS_MOTION,V1.0", "#WEBOTS_MOTION,V2.0", "#WEBOTS"]))
    sep = draw(st.sampled_from([",", "\n", "\r\n"]))
    lines = [head + sep + ",".join(joints)]
    t = draw(st.integers(0, 10**6))
    for _ in range(draw(st.integers(0, 6))):
        t += draw(st.integers(-50, 10**5))
        time = draw(st.one_of(st.just(f"{t // 60000:02d}:{t // 1000 % 60:02d}:{t % 1000:03d}"),
                              st.just(str(t)), st.sampled_from(["99999999999", "1:2:3:4",
                                                                "::", "0x10", "-5"])))
        vals = draw(st.lists(number_text, min_size=0, max_size=len(joints) + 1))
        lines.append(",".join([time, draw(st.sampled_from(["P", "", "Pose\u00e9"])), *vals]))
    return "\n".join(lines).encode() + draw(st.sampled_from([b"", b"\n", b"\xff", b"\x00"]))


@st.composite
def scenario_text(draw) -> bytes:
    rows = draw(st.lists(st.lists(st.one_of(number_text, st.sampled_from(["1", "2", "3", "0",
                                                                          "360", "#"])),
                                  min_size=0, max_size=4), min_size=0, max_size=30))
    return "\n".join(" ".join(r) for r in rows).encode()


@st.composite
def movingai_text(draw) -> bytes:
    h = draw(st.one_of(st.integers(-1, 6), st.sampled_from([10**9, 8193])))
    w = draw(st.one_of(st.integers(-1, 6), st.sampled_from([10**9, 8192])))
    head = [f"type {draw(st.sampled_from(['octile', 'hex']))}",
            f"height {draw(st.sampled_from([str(h), 'x', '3.5', '']))}", f"width {w}", "map"]
    head = draw(st.permutations(head)) if draw(st.booleans()) else head
    rows = draw(st.lists(st.text(alphabet=".@GSOTW x\t\r\u00e9", max_size=8), max_size=8))
    return "\n".join([*head, *rows]).encode() + draw(st.sampled_from([b"", b"\n", b"\xfe"]))


@st.composite
def binary_text(draw) -> bytes:
    rows = draw(st.lists(st.text(alphabet="0101 ,\t2a\r", max_size=8), max_size=8))
    return "\n".join(rows).encode() + draw(st.sampled_from([b"", b"\n", b"\x80"]))


json_leaf = st.one_of(st.none(), st.booleans(), st.integers(-10**30, 10**30), any_float,
                      st.text(max_size=6))
json_value = st.recursive(json_leaf, lambda c: st.one_of(st.lists(c, max_size=4),
                                                         st.dictionaries(st.text(max_size=4),
                                                                         c, max_size=4)),
                          max_leaves=12)


@st.composite
def plan_text(draw) -> bytes:
    """The valid plan with 1 to 3 values (anywhere in the tree) replaced by random JSON."""
    doc = json.loads(SEEDS["plan"][0])
    for _ in range(draw(st.integers(1, 3))):
        node, key = None, None
        cur = doc
        while isinstance(cur, dict | list) and cur and (node is None or draw(st.booleans())):
            keys = list(cur) if isinstance(cur, dict) else list(range(len(cur)))
            node, key = cur, draw(st.sampled_from(keys))
            cur = cur[key]
        if node is None:
            doc = draw(json_value)
        elif draw(st.integers(0, 4)) == 0:
            del node[key]
        else:
            node[key] = draw(json_value)
    return json.dumps(doc, allow_nan=True).encode()


@st.composite
def world_text(draw) -> bytes:
    words = ["name", "bounds", "start", "goal", "view", "nostep", "obstacle", "hidden", "x", ""]
    rows = []
    for _ in range(draw(st.integers(0, 8))):
        key = draw(st.sampled_from(words))
        vals = draw(st.lists(st.one_of(number_text, st.integers(-20, 20).map(str)),
                             max_size=10))
        rows.append(" ".join([key, *vals]) + draw(st.sampled_from(["", " # c", "\r"])))
    return "\n".join(rows).encode() + draw(st.sampled_from([b"", b"\n", b"\xfe"]))


GRAMMARS = {"motion": motion_text(), "scenario": scenario_text(), "movingai": movingai_text(),
            "binary": binary_text(), "plan": plan_text(), "world": world_text()}


@pytest.mark.parametrize("reader", sorted(READERS))
def test_generated_files(reader, tmp_path):
    @settings(max_examples=PROPERTY_EXAMPLES, **FUZZ)
    @given(GRAMMARS[reader])
    def check(data):
        _run(reader, tmp_path, data)

    check()
