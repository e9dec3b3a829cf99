"""One way of making matplotlib figures: a ``Figure`` on the Agg canvas (no pyplot state, no display),
saved as PNG atomically; axis labels that carry their units, and legends that cover no data."""

from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..run.persistence import save_figure_bytes

if TYPE_CHECKING:
    from matplotlib.axes import Axes
    from matplotlib.figure import Figure
    from matplotlib.legend import Legend
    from pydantic.fields import FieldInfo

__all__ = ["new_figure", "subplots", "save_figure", "axis_label", "quantity_unit", "legend_outside", "DIMENSIONLESS"]

#: the unit an axis label gives a dimensionless quantity (a ratio, a probability, a count)
DIMENSIONLESS = "-"

# the study quantities that are not fields of a run's summary or history
_STUDY_UNITS = {"convergence_speed": "m/s", "critical_velocity": "m/s", "characteristic_convergent_velocity": "m/s"}


def new_figure(figsize: tuple[float, float], dpi: float | None = None) -> Figure:
    """A matplotlib ``Figure`` drawn by the Agg canvas (off-screen), outside pyplot's figure manager."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=figsize, dpi=dpi)
    FigureCanvasAgg(figure)
    return figure


def subplots(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float], **kwargs: Any) -> tuple[Figure, Any]:
    """``(figure, axes)`` as ``pyplot.subplots`` gives them, on a :func:`new_figure`."""
    # axes: one Axes or an array of them, by nrows, ncols and squeeze (matplotlib types it Any too)
    figure = new_figure(figsize)
    return figure, figure.subplots(nrows, ncols, **kwargs)


def save_figure(figure: Figure, path: str | os.PathLike, dpi: int = 110) -> Path:
    """Save ``figure`` as a PNG file, written atomically (a reader never sees a part of it)."""
    return save_figure_bytes(figure, path, dpi)


def axis_label(name: str, unit: str | None) -> str:
    """``name (unit)``; a dimensionless quantity (unit ``""``, ``"1"`` or ``"-"``) is ``name (-)``.

    ``unit = None`` (a quantity of unknown unit) gives ``name`` alone rather than a made-up unit.
    """
    if unit is None:
        return name
    return f"{name} ({unit if unit not in ('', '1') else DIMENSIONLESS})"


def quantity_unit(name: str) -> str | None:
    """The unit of a named quantity, as the project records it; ``""`` for a dimensionless one.

    ``name`` is a field of a run's summary (``depth``: ``m``), a column of its history
    (``speed``: ``m/s``), a study quantity (``critical_velocity``: ``m/s``) or a dotted scene key
    (``impact.speed``: ``m/s``, ``target.law.B``: dimensionless).  None if it is none of these.
    """
    from ..run import HISTORY_UNITS
    from ..run.summary import RunSummary
    from ..scene.explain import _field_at  # the schema walk that names fields in error messages

    if name in _STUDY_UNITS:
        return _STUDY_UNITS[name]
    if name in RunSummary.model_fields:
        return _recorded_unit(RunSummary.model_fields[name])
    if name in HISTORY_UNITS:
        return HISTORY_UNITS[name]
    info, _, _ = _field_at(tuple(name.split(".")))
    if info is None:
        return None
    return _recorded_unit(info)


def _recorded_unit(info: FieldInfo) -> str:
    """The unit a model field records (``json_schema_extra["unit"]``), ``""`` when it records none."""
    extra = info.json_schema_extra or {}
    assert isinstance(extra, dict)  # the project's fields record a dict, never a callable
    unit = extra.get("unit", "")
    assert isinstance(unit, str)
    return unit


def _nothing_labelled(ax: Axes, kwargs: dict[str, Any]) -> bool:
    """No handles given and no labelled artist on ``ax`` (e.g. an ensemble whose bins are all empty): the
    legend helpers then draw no empty legend box."""
    return "handles" not in kwargs and not ax.get_legend_handles_labels()[0]


def legend_outside(ax: Axes, **kwargs: Any) -> Legend | None:
    """A legend right of ``ax``, outside its data area, so it covers no data.

    ``loc="best"`` only picks the least crowded spot inside the axes, and covers data when there
    is none free (probability bands spanning the plot).  ``figure.tight_layout()`` afterwards
    leaves room for the legend.  ``kwargs`` go to ``Axes.legend`` (``fontsize`` 8 unless given).
    """
    if _nothing_labelled(ax, kwargs):
        return None
    kwargs.setdefault("fontsize", 8)
    return ax.legend(loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0, **kwargs)


def legend_below(ax: Axes, **kwargs: Any) -> Legend | None:
    """A legend under ``ax``'s x label, outside its data area: for axes with a twin on the right or a
    neighbour beside them, where :func:`legend_outside` would cover them.  ``kwargs`` go to ``Axes.legend``
    (``fontsize`` 8 and two columns unless given)."""
    if _nothing_labelled(ax, kwargs):
        return None
    kwargs.setdefault("fontsize", 8)
    kwargs.setdefault("ncol", 2)
    return ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.16), borderaxespad=0.0, **kwargs)
