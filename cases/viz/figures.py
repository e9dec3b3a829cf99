"""One way of making matplotlib figures: a ``Figure`` on the Agg canvas (no pyplot state, no display),
saved as PNG atomically."""

from __future__ import annotations

import os
from pathlib import Path

from ..run.persistence import save_figure_bytes

__all__ = ["new_figure", "subplots", "save_figure"]


def new_figure(figsize: tuple[float, float], dpi: float | None = None):
    """A matplotlib ``Figure`` drawn by the Agg canvas (off-screen), outside pyplot's figure manager."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    figure = Figure(figsize=figsize, dpi=dpi)
    FigureCanvasAgg(figure)
    return figure


def subplots(nrows: int = 1, ncols: int = 1, *, figsize: tuple[float, float], **kwargs):
    """``(figure, axes)`` as ``pyplot.subplots`` gives them, on a :func:`new_figure`."""
    figure = new_figure(figsize)
    return figure, figure.subplots(nrows, ncols, **kwargs)


def save_figure(figure, path: str | os.PathLike, dpi: int = 110) -> Path:
    """Save ``figure`` as a PNG file, written atomically (a reader never sees a part of it)."""
    return save_figure_bytes(figure, path, dpi)
