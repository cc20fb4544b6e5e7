"""The new-run form's fields (issue 35): TOML values (not Python's), short floats that count
as unchanged, every key's documentation, registry choices, common/advanced groups, and every
error at once."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from evomotion.run.config import RunSection, parse_value
from evomotion.studio import actions
from evomotion.studio import form_schema as fs

_scalars = st.one_of(st.booleans(), st.integers(-10**6, 10**6),
                     st.floats(allow_nan=False, allow_infinity=False),
                     st.text(st.characters(codec="utf-8", exclude_categories=("Cs", "Cc")),
                             max_size=12))
_values = st.recursive(_scalars, lambda c: st.one_of(
    st.lists(c, max_size=3), st.dictionaries(st.from_regex(r"[a-z_]{1,6}", fullmatch=True),
                                             c, max_size=3)), max_leaves=8)


@settings(max_examples=300, deadline=None)
@given(_values)
def test_toml_text_is_what_set_parses_back(v):
    text = fs.toml_text(v)
    back = parse_value(text)
    if isinstance(v, str) and text.strip().lower() == '"none"':
        return
    assert back == v or (isinstance(v, float) and math.isclose(back, v))


def test_dicts_are_inline_tables_and_long_floats_are_short():
    assert fs.toml_text({"k": 10, "delta": 0.08}) == "{k = 10, delta = 0.08}"
    assert fs.toml_text({"a b": "x"}) == '{"a b" = "x"}'
    assert fs.shown_text("float", math.pi / 4) == "0.785398"
    assert fs.shown_text("float", 0.08) == "0.08" and fs.shown_text("str", "a b") == "a b"


def test_a_shortened_float_left_alone_is_no_change_and_an_edited_one_is():
    f = actions.FormField("problem.x", "float", repr(math.pi / 4), shown="0.785398")
    assert actions.changed_sets([f], {"problem.x": "0.785398"}) == []
    assert actions.changed_sets([f], {"problem.x": "0.5"}) == ["problem.x=0.5"]


def test_every_run_key_is_documented_and_registries_are_selects():
    docs = fs.field_docs(RunSection)
    missing = [k for k in RunSection.__dataclass_fields__ if not docs.get(k)]
    assert not missing, missing
    assert "0: no limit" in docs["wall_seconds"] and "(s;" in docs["wall_seconds"]
    fields = {f.key: f for f in actions.form_fields("humanoid-step")}
    assert set(fields["run.evaluator"].choices) >= {"serial", "process"}
    assert "blx_alpha" in fields["algorithm.crossover"].choices
    assert fields["algorithm.crossover_params"].shown.startswith("{")
    assert "nao" in fields["problem.robot"].choices and fields["problem.robot"].free
    assert "(s; paper: 1)" in fields["problem.hold_s"].doc
    # common: the run's budget and what the paper preset sets; the rest is advanced
    assert fields["run.seed"].common and fields["problem.intervals"].common
    assert not fields["run.chunks_per_worker"].common
    # a preset's own setting on an environment counts too (gym's paper Swimmer: V1, no
    # normalisation), and the fields show that setting
    gym = {f.key: f for f in actions.form_fields("gym", "paper", None, "Swimmer-v5")}
    assert gym["problem.normalize"].common and gym["problem.normalize"].shown == "false"
    assert gym["algorithm.pop_size"].shown == "2"
    assert gym["problem.env"].common  # the key that picks the defaults: shown first


def test_every_error_of_the_form_at_once_under_its_field():
    keys = [f.key for f in actions.form_fields("functions")]
    errors = actions.form_errors("functions", None, ["algorithm.pop_size=-4",
                                                     "run.generations=-1", "run.seed=3"], keys)
    assert set(errors) == {"algorithm.pop_size", "run.generations"}
    assert all("\n" not in e for e in errors.values())
    assert actions.form_errors("functions", None, ["run.seed=3"], keys) == {}
