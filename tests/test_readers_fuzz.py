"""Fuzzing the shared bounded readers (issue 31): whatever the bytes, one InputError or a
value within the documented limits; never RecursionError, MemoryError or a block."""

from __future__ import annotations

import contextlib
import io
import json
import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.errors import InputError
from evomotion.run.archive_file import read_archive
from evomotion.run.history import read_history
from evomotion.textio import MAX_JSON_DEPTH, json_depth, loads_json

JSON = st.recursive(
    st.none() | st.booleans() | st.integers() | st.floats(allow_nan=True) | st.text(max_size=8),
    lambda kids: st.lists(kids, max_size=4) | st.dictionaries(st.text(max_size=4), kids,
                                                              max_size=4),
    max_leaves=40)


def _finite(doc) -> bool:
    if isinstance(doc, float):
        return math.isfinite(doc)
    if isinstance(doc, list):
        return all(_finite(v) for v in doc)
    if isinstance(doc, dict):
        return all(_finite(v) for v in doc.values())
    return True


@settings(max_examples=300, deadline=None)
@given(JSON, st.integers(min_value=0, max_value=60))
def test_loads_json_accepts_exactly_the_finite_shallow_documents(doc, wrap):
    text = "[" * wrap + json.dumps(doc, allow_nan=True) + "]" * wrap
    depth = json_depth(text, 10**6)
    try:
        out = loads_json(text, "f.json")
    except InputError:
        assert depth > MAX_JSON_DEPTH or not _finite(doc)
        return
    assert depth <= MAX_JSON_DEPTH and _finite(doc)
    for _ in range(wrap):
        out = out[0]
    assert json.dumps(out) == json.dumps(doc)


@settings(max_examples=300, deadline=None)
@given(st.text(alphabet='[]{}":,0123456789.eE-+tfnaNIul\\ x', max_size=400))
def test_loads_json_on_json_like_noise(text):
    with contextlib.suppress(InputError):
        loads_json(text, "f.json")


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=2000))
def test_read_history_on_random_bytes(tmp_path_factory, data):
    p = tmp_path_factory.mktemp("h") / "population.bin"
    p.write_bytes(data)
    try:
        for g, pop, fit in read_history(p):
            assert pop.ndim == 2 and fit.shape == (pop.shape[0],)
    except InputError:
        pass


def _archive(**over) -> bytes:
    a = dict(kind=np.array("grid"), bins=np.array([2, 2]), cells=np.array(4),
             lower=np.zeros(2), upper=np.ones(2), measure_names=np.array(["a", "b"]),
             cell=np.array([0, 3]), centre=np.full((2, 2), 0.5), solution=np.zeros((2, 3)),
             objective=np.zeros(2), measures=np.full((2, 2), 0.5), all_centres=np.zeros((4, 2)))
    a.update(over)
    buf = io.BytesIO()
    np.savez(buf, **a)
    return buf.getvalue()


@settings(max_examples=120, deadline=None)
@given(st.sampled_from(["bins", "cells", "lower", "upper", "cell", "objective", "centre"]),
       st.one_of(st.integers(-2**63, 2**63 - 1), st.floats(allow_nan=True),
                 st.lists(st.integers(-2**40, 2**40), max_size=5)))
def test_read_archive_on_damaged_fields(tmp_path_factory, key, value):
    p = tmp_path_factory.mktemp("a") / "archive.npz"
    p.write_bytes(_archive(**{key: np.array(value)}))
    try:
        a = read_archive(p)
    except InputError:
        return
    assert np.all(np.isfinite(a.objective)) and np.all(a.lower < a.upper)
    assert np.all((a.cell >= 0) & (a.cell < a.cells))


@settings(max_examples=150, deadline=None)
@given(st.binary(max_size=3000), st.integers(0, 2999))
def test_read_archive_on_flipped_bytes(tmp_path_factory, noise, at):
    data = bytearray(_archive())
    data[at % len(data):at % len(data) + len(noise)] = noise
    p = tmp_path_factory.mktemp("a") / "archive.npz"
    p.write_bytes(bytes(data))
    with contextlib.suppress(InputError):
        read_archive(p)
