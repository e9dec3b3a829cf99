"""``penetrate map``: the critical impact velocity, or the ballistic limit, over a grid of one or two scene inputs.

Each point of the grid is a critical-speed search of the scene with those inputs set
(:func:`~cases.studies.speeds.characteristic.find_critical_velocities`, all points in lockstep on the pool's workers),
guided by the reduced model where it applies and confirmed by full runs; or, with ``quantity =
"ballistic_limit"``, a ballistic-limit search (:func:`~cases.studies.speeds.ballistic.find_ballistic_limit`, point after
point, each on the pool's workers).  The runs are kept in the run
store, so an interrupted map resumes: its searches replay their rounds from the store and run only what is
missing.  The study writes ``map.csv`` (a row per point), ``map.json``, ``map.md`` and ``map.png`` (a
contour of the critical speed over two inputs, or a curve over one).
"""

from __future__ import annotations

import math
import os
import time
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from ...run import RunStore
from ...run.persistence import json_safe
from ...scene import InputError, Overrides
from ...viz.figures import axis_label, quantity_unit, save_figure, subplots
from ..engine.pool import Pool
from ..engine.report import Report, markdown_table, number_cell, write_report
from ..engine.sweep import Sweep, grid, parse_grid
from .ballistic import find_ballistic_limit
from .characteristic import find_critical_velocities

__all__ = ["stability_map", "MAX_POINTS", "QUANTITIES"]

MAX_POINTS = 10_000  # points of one map
#: what a map can show, with its title
QUANTITIES = {"critical_velocity": "critical impact velocity", "ballistic_limit": "ballistic limit"}


def _axes(axes_given: Sequence[str]) -> list[tuple[str, list[Any]]]:
    """The ``--grid KEY=VALUES`` options as (key, values), one or two distinct keys, not the impact speed."""
    if not 1 <= len(axes_given) <= 2:
        raise InputError(f"--grid: give one or two (KEY=START:STOP:STEP or KEY=V1,V2,...), got {len(axes_given)}")
    axes = [parse_grid(text, "--grid") for text in axes_given]
    keys = [key for key, _ in axes]
    if len(set(keys)) != len(keys):
        raise InputError(f"--grid: {keys[0]} given twice (allowed: two different keys)")
    if "impact.speed" in keys:
        raise InputError(
            "--grid impact.speed: the map searches the impact speed; map other inputs (--speeds sets its range)"
        )
    points = math.prod(len(values) for _, values in axes)
    if points > MAX_POINTS:
        raise InputError(f"--grid: {points} points (allowed: at most {MAX_POINTS})")
    return axes


def stability_map(
    scene: str | os.PathLike,
    overrides: Overrides | None,
    axes_given: Sequence[str],
    store: RunStore,
    out: str | os.PathLike,
    speeds: tuple[float, float] = (200.0, 1600.0),
    resolution: float = 5.0,
    pool: Pool | None = None,
    guide: str = "auto",
    quantity: str = "critical_velocity",
) -> dict:
    """The critical impact velocity (or the ballistic limit) at every point of the grid ``axes_given``; writes the map
    into ``out``.

    Parameters
    ----------
    scene, overrides
        The base scene file and its ``--set`` overrides.
    axes_given : sequence of str
        One or two ``KEY=START:STOP:STEP`` (inclusive) or ``KEY=V1,V2,...``: the grid's axes.
    store : RunStore
        Where runs are found and kept (a map resumes from it).
    out : path
        Where ``map.csv``, ``map.json``, ``map.md`` and ``map.png`` go.
    speeds, resolution, guide
        As ``penetrate critical`` (or ``penetrate ballistic-limit``) takes them (m/s).
    quantity : {"critical_velocity", "ballistic_limit"}
        What each point searches.

    Returns
    -------
    dict
        ``{"keys", "values", "quantity", "points": [{KEY: value, ..., QUANTITY, "bracket", "runs", "guide"}],
        ...}``.
    """
    start = time.perf_counter()
    axes = _axes(axes_given)
    keys = [key for key, _ in axes]
    points_grid = grid(dict(axes))  # the last key varies fastest
    bases = [Sweep.from_file(scene, overrides, [variation]) for variation in points_grid]
    # each point's (value, bracket, full runs, guide, predicted speed, message)
    if quantity == "ballistic_limit":
        limits = [find_ballistic_limit(base, store, speeds, resolution, pool, guide != "none") for base in bases]
        found = [
            (
                s.ballistic_limit,
                s.bracket,
                len(s.runs),
                "none" if s.predicted is None else "1-D",
                s.predicted,
                s.message,
            )
            for s in limits
        ]
    else:
        searches = find_critical_velocities(bases, store, speeds, resolution, pool, guide=guide)
        found = [
            (s.critical_velocity, s.bracket, len(s.indicator), s.guide.name, s.guide.predicted, s.message)
            for s in searches
        ]
    names = (quantity, "bracket", "runs", "guide", "predicted_velocity", "message")
    points = [{**variation.values, **dict(zip(names, point))} for variation, point in zip(points_grid, found)]
    record = {
        "scene": str(scene),
        "quantity": quantity,
        "keys": keys,
        "values": [values for _, values in axes],
        "speeds": list(speeds),
        "resolution": resolution,
        "points": points,
        "full_runs": sum(p["runs"] for p in points),
        "guided": sum(p["guide"] != "none" for p in points),
        "wall_time": time.perf_counter() - start,
    }
    _write(Path(out), record)
    return json_safe(record)


def _write(out: Path, record: dict) -> None:
    import pandas as pd

    table = pd.DataFrame(record["points"])
    table[["bracket_low", "bracket_high"]] = [b if b else [math.nan, math.nan] for b in table.pop("bracket")]
    figures = {"map.png": lambda path: _figure(record, path)}
    write_report(out, Report("map", _markdown(record), table, {**record, "wall_time": None}, figures))


def _markdown(record: dict) -> str:
    keys, quantity = record["keys"], record["quantity"]
    title, guide = QUANTITIES[quantity], "the reduced model" if quantity == "critical_velocity" else "the 1-D model"
    lines = [
        f"# {title.capitalize()} of {record['scene']} over {' and '.join(keys)}",
        "",
        f"{len(record['points'])} searches in {record['speeds'][0]:g}-{record['speeds'][1]:g} m/s to"
        f" {record['resolution']:g} m/s, {record['guided']} guided by {guide}, {record['full_runs']} full"
        f" runs in all. A point without a {title} says why.",
        "",
    ]
    rows = []
    for p in record["points"]:
        bracket = " - ".join(number_cell(bound, "g") for bound in p["bracket"]) if p["bracket"] else "-"
        # float(): an integer grid value too is drawn as %g (1e+08, not 100000000)
        cells = [number_cell(float(p[k]), "g") for k in keys]
        rows.append([*cells, number_cell(p[quantity], ".1f", missing=p["message"]), bracket, p["runs"], p["guide"]])
    lines += markdown_table([*keys, f"{title} (m/s)", "bracket (m/s)", "full runs", "guide"], rows)
    lines += ["", "![the map](map.png)", ""]
    return "\n".join(lines)


def _figure(record: dict, path: Path) -> None:
    keys, values, quantity = record["keys"], record["values"], record["quantity"]
    critical = np.array([np.nan if p[quantity] is None else p[quantity] for p in record["points"]])
    fig, ax = subplots(1, 1, figsize=(7.0, 4.6))
    label = axis_label(QUANTITIES[quantity], "m/s")
    if len(keys) == 1:
        ax.plot(np.asarray(values[0], dtype=float), critical, marker="o")
        ax.set(xlabel=axis_label(keys[0], quantity_unit(keys[0])), ylabel=label)
    else:
        x, y = (np.asarray(v, dtype=float) for v in values)
        z = critical.reshape(len(x), len(y)).T
        if len(x) > 1 and len(y) > 1 and np.isfinite(z).sum() >= 3:
            filled = ax.contourf(x, y, np.ma.masked_invalid(z), levels=12, cmap="viridis")
            fig.colorbar(filled, ax=ax, label=label)
        ax.scatter(*np.meshgrid(x, y), c="k", s=6, zorder=3, clip_on=False)
        ax.set(xlabel=axis_label(keys[0], quantity_unit(keys[0])), ylabel=axis_label(keys[1], quantity_unit(keys[1])))
    ax.set_title(f"{QUANTITIES[quantity]} (points without one left blank)")
    ax.grid(alpha=0.3)
    fig.tight_layout()
    save_figure(fig, path)
