"""How every study puts its results in words: one Markdown table formatter and one number cell.

A study builds its rows as cells (strings, or numbers through :func:`number_cell`) and :func:`markdown_table`
draws them, so that every report's tables have one form and a missing or non-finite value reads ``-`` in all of
them.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Sequence
from typing import Any

__all__ = ["markdown_table", "number_cell"]


def number_cell(value: Any, spec: str = ".3g", missing: str = "-") -> str:
    """``format(value, spec)`` for a float, ``str(value)`` for anything else (an integer, a word), and ``missing``
    for ``None`` or a non-finite float."""
    if value is None:
        return missing
    if isinstance(value, float):  # numpy's float64 is a float too
        return format(value, spec) if math.isfinite(value) else missing
    return str(value)


def markdown_table(header: Sequence[str], rows: Iterable[Sequence[Any]]) -> list[str]:
    """The lines of a Markdown table: ``header``, its rule and one line per row (each cell ``str()``-ed; an empty
    cell is drawn ``| |``)."""

    def line(cells: Sequence[Any]) -> str:
        return "|" + "".join(f" {cell} |" if str(cell) else " |" for cell in cells)

    rule = "|---|" + "---|" * (len(header) - 1)
    return [line(header), rule, *(line(row) for row in rows)]
