"""How every study reports: a :class:`Report` (its table, record, Markdown and figures), the one writer that puts
it on disk, one Markdown table formatter and one number cell.

A study builds its rows as cells (strings, or numbers through :func:`number_cell`) and :func:`markdown_table`
draws them, so that every report's tables have one form and a missing or non-finite value reads ``-`` in all of
them.  It writes no file itself: :func:`write_report` writes each of its files atomically, the record through
the one JSON writer (non-finite numbers as ``null``) and each figure through the one figure saver.
"""

from __future__ import annotations

import math
import os
from collections.abc import Callable, Iterable, Mapping, Sequence
from dataclasses import dataclass, field
from pathlib import Path
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:
    import pandas as pd

__all__ = ["Report", "write_report", "markdown_table", "number_cell"]


@dataclass
class Report:
    """What a study says, under the stem ``name``: its Markdown (``NAME.md``), its ``table`` (``NAME.csv``, a row
    per run or point), its ``record`` (``NAME.json``) and its ``figures`` (file name -> a function that draws the
    figure into the path it is given, through :func:`~cases.viz.figures.save_figure`)."""

    name: str
    markdown: str
    table: pd.DataFrame | None = None
    record: Mapping[str, Any] | None = None
    figures: Mapping[str, Callable[[Path], None]] = field(default_factory=dict)

    def files(self) -> list[str]:
        """The names of the files the report writes, in the order they are written."""
        names = [f"{self.name}.csv"] if self.table is not None else []
        names += [f"{self.name}.json"] if self.record is not None else []
        return [*names, f"{self.name}.md", *self.figures]


def write_report(out: str | os.PathLike, report: Report, width: int = 1) -> list[Path]:
    """Write ``report`` into the folder ``out`` (made if missing), each file atomically: the one way a study puts
    its report on disk.  Returns the paths written.

    ``width`` > 1 draws the figures on that many local processes (the study's warm workers,
    :func:`~.pool.map_local`): each figure function must then be a module's function with its data bound
    (``functools.partial``), which a process can be sent.  A figure costs about half a second, most of it
    matplotlib's drawing."""
    from ...run import atomic_write_text, write_json
    from .pool import map_local

    folder = Path(out)
    folder.mkdir(parents=True, exist_ok=True)
    if report.table is not None:
        atomic_write_text(folder / f"{report.name}.csv", report.table.to_csv(index=False))
    if report.record is not None:
        write_json(folder / f"{report.name}.json", report.record)
    atomic_write_text(folder / f"{report.name}.md", report.markdown)
    map_local(_draw, [(draw, folder / name) for name, draw in report.figures.items()], width)
    return [folder / name for name in report.files()]


def _draw(draw: Callable[[Path], None], path: Path) -> None:
    """One figure of a report (a job of :func:`~.pool.map_local`)."""
    draw(path)


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
