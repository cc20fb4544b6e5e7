"""A markdown table as the benchmark scripts print it (imported by the scripts beside it)."""

from __future__ import annotations

from collections.abc import Sequence


def markdown_table(head: Sequence[str], rows: Sequence[Sequence[str]]) -> str:
    """``| a | b |`` lines: the header, its rule, one line per row."""
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    return "\n".join(lines + [markdown_row(r) for r in rows])


def markdown_row(row: Sequence[str]) -> str:
    """One row's ``| a | b |`` line (printed as it is measured, before the whole table)."""
    return "| " + " | ".join(row) + " |"
