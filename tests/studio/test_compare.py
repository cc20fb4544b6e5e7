"""The comparison's config diff, group-by keys and URL (issue 35), without a browser."""

from __future__ import annotations

from evomotion.studio import compare


def _flat(study="functions", seed=0, alg="ga", pop=10, preset=None):
    raw = {"study": study, "run": {"seed": seed, "target": None},
           "algorithm": {"name": alg, "pop_size": pop, "params": {"eta": 15.0}}}
    if preset:
        raw["preset"] = preset
    return compare.flat_config(raw)


def test_flat_config_writes_values_as_set_takes_them():
    f = _flat()
    assert f["run.seed"] == "0" and f["algorithm.name"] == "ga" and f["preset"] == "default"
    assert f["algorithm.params.eta"] == "15.0" and f["run.target"] == "none"


def test_only_differing_keys_in_the_diff_study_and_preset_first():
    flat = [_flat(seed=0), _flat(seed=1, preset="paper"), _flat(seed=2, pop=20)]
    assert compare.differing_keys(flat) == ["preset", "run.seed", "algorithm.pop_size"]
    cols, rows = compare.diff_table(["a", "b", "c"], flat)
    assert [c["label"] for c in cols] == ["key", "a", "b", "c"]
    assert rows[1] == {"key": "run.seed", "r0": "0", "r1": "1", "r2": "2"}
    assert compare.differing_keys([_flat(), _flat()]) == []


def test_groups_never_cross_studies_and_choices_include_differing_keys():
    a, b = _flat(study="functions", alg="ga"), _flat(study="grid-path", alg="ga")
    assert compare.group_label(a, "algorithm.name") != compare.group_label(b, "algorithm.name")
    assert compare.group_label(a, "study") == "functions"
    assert compare.group_label(a, "run.seed") == "functions · run.seed = 0"
    choices = compare.group_choices([_flat(pop=10), _flat(pop=20)])
    assert choices[:4] == list(compare.ALWAYS) and "algorithm.pop_size" in choices


def test_the_url_holds_the_selection_and_the_grouping():
    assert compare.page_url(["a b", "c"], "study") == "/compare?runs=a%20b,c"
    assert compare.page_url(["a"], "run.seed") == "/compare?runs=a&by=run.seed"
