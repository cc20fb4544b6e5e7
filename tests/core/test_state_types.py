"""A checkpoint's state is read back with the types its fields declare: a string, null or a
bool where a number is declared, or text where an array is, is refused naming the field (a
resume then skips that checkpoint in one line) instead of failing in the next generation."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from evomotion.core.state import checked_fields, state_from_arrays, state_to_arrays


@dataclass(frozen=True)
class Inner:
    cost: float
    x: np.ndarray


@dataclass(frozen=True)
class State:
    generation: int
    sigma: float
    flag: bool
    name: str
    x: np.ndarray
    inner: Inner
    maybe: float | None = None
    anything: Any = None


def _good() -> State:
    return State(3, 0.5, True, "a", np.arange(3.0), Inner(float("inf"), np.ones(2)))


def test_a_state_round_trips_and_json_numbers_are_numbers():
    arrays, meta = state_to_arrays(_good())
    back = state_from_arrays(State, arrays, meta)
    assert back.generation == 3 and back.inner.cost == float("inf")
    assert np.array_equal(back.x, np.arange(3.0))
    meta["sigma"] = 1  # an int where a float is declared (JSON writes 1.0 as 1 elsewhere)
    meta["generation"] = 3.0  # a whole float where an int is (an older writer)
    assert state_from_arrays(State, arrays, meta).sigma == 1


@pytest.mark.parametrize("key, value, message", [
    ("generation", "x", "state field 'generation': expected a number, got 'x'"),
    ("sigma", None, "state field 'sigma': expected a number, got None"),
    ("sigma", True, "state field 'sigma': expected a number, got True"),
    ("flag", 1, "state field 'flag': expected true or false, got 1"),
    ("name", 5, "state field 'name': expected a string, got 5"),
    ("inner.cost", [1], "state field 'inner.cost': expected a number, got [1]"),
    ("maybe", "y", "state field 'maybe': expected a number or null, got 'y'"),
])
def test_a_value_of_another_type_is_refused_naming_the_field(key, value, message):
    arrays, meta = state_to_arrays(_good())
    meta[key] = value
    with pytest.raises(TypeError, match=message.replace("[", r"\[").replace("]", r"\]")):
        state_from_arrays(State, arrays, meta)


def test_an_array_of_text_is_refused():
    arrays, meta = state_to_arrays(_good())
    arrays["inner.x"] = np.array(["a", "b"])
    with pytest.raises(TypeError, match="state field 'inner.x': expected a numeric array"):
        state_from_arrays(State, arrays, meta)


def test_numpy_scalars_and_zero_d_arrays_read_back_as_they_were_written():
    """An array field holding a numpy scalar (``0-d + 0-d`` is one) goes to the JSON as a
    number, a number field holding a 0-d array to the npz: both resume as before."""
    s = State(np.int64(3), np.array(0.5), np.array(True), "a", np.float64(2.0),
              Inner(1.0, np.ones(2)))
    arrays, meta = state_to_arrays(s)
    assert meta["x"] == 2.0 and arrays["sigma"].shape == ()
    back = state_from_arrays(State, arrays, meta)
    assert back.x == 2.0 and back.sigma == 0.5 and back.flag


def test_checked_fields_checks_a_top_level_built_by_hand():
    assert checked_fields(State, {"generation": 2, "anything": object})["generation"] == 2
    with pytest.raises(TypeError, match="'generation'"):
        checked_fields(State, {"generation": None})


@given(st.one_of(st.none(), st.booleans(), st.integers(), st.floats(), st.text(max_size=3),
                 st.lists(st.integers(), max_size=2)))
def test_any_json_value_for_a_number_is_a_number_or_a_type_error(value):
    arrays, meta = state_to_arrays(_good())
    meta["sigma"] = value
    try:
        back = state_from_arrays(State, arrays, meta)
    except TypeError as e:
        assert "state field 'sigma'" in str(e)
    else:
        assert isinstance(back.sigma, int | float) and not isinstance(back.sigma, bool)
