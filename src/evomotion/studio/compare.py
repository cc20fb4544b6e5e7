"""What the comparison page needs beyond the curves (issue 35): the selected runs' configs
flattened to ``section.key`` values, the keys on which they differ (the config-diff table and
the "group by" choices), a run's group under such a key (never across studies), and the page's
URL for a selection."""

from __future__ import annotations

from pathlib import Path
from typing import Any
from urllib.parse import quote

#: group-by choices offered whatever the runs: the study alone, or with these keys
ALWAYS = ("study", "preset", "algorithm.name", "run.seed")
MISSING = "-"
#: the diff's rows: the study, the preset, then the sections' keys
ORDER = {"study": 0, "preset": 1, "run": 2, "algorithm": 3, "problem": 4}


def flat_config(raw: dict[str, Any]) -> dict[str, str]:
    """``{"study": ..., "preset": ..., "run.seed": "0", ...}`` of a config table (values as
    their TOML-like text; nested tables as ``a.b.c`` keys)."""
    from evomotion.studio.form_schema import toml_text

    out: dict[str, str] = {}

    def walk(prefix: str, v: Any) -> None:
        if isinstance(v, dict):
            for k, x in v.items():
                walk(f"{prefix}.{k}" if prefix else str(k), x)
        else:
            out[prefix] = v if isinstance(v, str) else toml_text(v)

    walk("", raw if isinstance(raw, dict) else {})
    out.setdefault("preset", "default")
    return out


def configs(run_dirs: list[Path]) -> list[dict[str, str]]:
    """Each run's :func:`flat_config` and its tags (key ``tags``: a group-by choice and a diff
    row where they differ)."""
    from evomotion.run.config import as_now
    from evomotion.studio.data import read_config
    from evomotion.studio.tags import read_tags

    out = []
    for d in run_dirs:
        flat = flat_config(as_now(read_config(d)[1]))  # a study renamed since: its name now
        flat["tags"] = " ".join(read_tags(d)) or MISSING
        out.append(flat)
    return out


def differing_keys(flat: list[dict[str, str]]) -> list[str]:
    """The keys whose values are not the same in every run (a key some runs lack counts),
    ``study`` and ``preset`` first, then in section order."""
    keys = sorted({k for c in flat for k in c},
                  key=lambda k: (ORDER.get(k.split(".")[0], len(ORDER)), k))
    return [k for k in keys if len({c.get(k, MISSING) for c in flat}) > 1]


def diff_table(names: list[str], flat: list[dict[str, str]]) -> tuple[list[dict], list[dict]]:
    """ECharts-free table of the differing keys: ``(columns, rows)`` for ``ui.table``."""
    cols = [{"name": "key", "label": "key", "field": "key", "align": "left"}]
    cols += [{"name": f"r{i}", "label": n, "field": f"r{i}", "align": "left"}
             for i, n in enumerate(names)]
    rows = [{"key": k, **{f"r{i}": c.get(k, MISSING) for i, c in enumerate(flat)}}
            for k in differing_keys(flat)]
    return cols, rows


def group_choices(flat: list[dict[str, str]]) -> list[str]:
    return list(dict.fromkeys([*ALWAYS, *(k for k in differing_keys(flat) if k != "study")]))


def group_label(conf: dict[str, str], by: str) -> str:
    """A run's group: its study, and the value of ``by`` unless ``by`` is the study."""
    study = conf.get("study", "?")
    return study if by == "study" else f"{study} · {by} = {conf.get(by, MISSING)}"


def page_url(names: list[str], by: str) -> str:
    """The comparison page's URL for a selection (written back as the selection changes)."""
    url = "/compare?runs=" + quote(",".join(names), safe=",")
    return url + (f"&by={quote(by)}" if by and by != "study" else "")
