"""``penetrate render``: everything drawn of one run, off-screen (images, trajectory, panels, GIF, ParaView)."""

from __future__ import annotations

import os
import time
from collections.abc import Iterable
from pathlib import Path

from ..run import RunResult
from .field import FieldEvaluator, frame_rows, resolve_instants
from .frames import field_ranges, render_animation, render_snapshots
from .panels import plot_histories, plot_polar
from .paraview import write_paraview
from .trajectory import render_trajectory, trajectory_rows

__all__ = ["render_all"]


def render_all(
    result: RunResult,
    out_dir: str | os.PathLike,
    times: Iterable[str] | None = None,
    *,
    animation: bool = False,
    paraview: bool = False,
    frames: int = 60,
    steps: int | None = 100,
    station: float | None = None,
    size: tuple[int, int] = (1280, 640),
    colour_range: tuple[float, float] | None = None,
) -> dict:
    """Everything ``penetrate render`` writes.

    Every picture of the field shares one colour range per field, so they compare: by default
    the min..max (MPa) over all the instants drawn (the field images, the bodies of
    ``trajectory.png`` and, with ``animation``, the animation's frames); ``colour_range`` fixes
    that of ``sigma_n`` (``tau``, with friction, keeps the shared range).  The ParaView files hold
    the values (Pa) and no colour scale.

    Parameters
    ----------
    result : RunResult
        The run.
    out_dir : path
        Folder to write into.
    times : iterable of str, optional
        Instants by name or time in seconds (:func:`resolve_instants`); the default instants if None.
    animation, paraview : bool
        Also write ``animation.gif`` and ``paraview/run.pvd`` with its files.
    frames : int
        Frames of the animation.
    steps : int or None
        Steps of the ParaView output (None: every recorded step).
    station : float, optional
        Distance behind the tip (m) of the polar plot's ring.
    size : (int, int)
        Size of the field images in pixels.
    colour_range : (float, float), optional
        Colour range of ``sigma_n`` (MPa), ``0 <= lo < hi``, for renders that compare with each other.

    Returns
    -------
    dict
        ``instants`` (label, row, time), ``colour_range`` (``{"sigma_n": [lo, hi]}`` and, with
        friction, ``tau``; MPa), ``files`` (written paths), ``seconds`` (wall time of each part and
        ``total``) and, with ``paraview``, ``paraview_steps``.
    """
    out = Path(out_dir)
    record: dict = {"files": [], "seconds": {}}
    start = time.perf_counter()
    evaluator = FieldEvaluator(result)
    instants = resolve_instants(evaluator, list(times) if times else None)
    record["instants"] = [
        {"label": label, "row": row, "time": float(evaluator.result.trajectory.time[row])} for label, row in instants
    ]
    t0 = time.perf_counter()
    drawn = [row for _, row in instants] + list(trajectory_rows(evaluator))
    if animation:
        drawn += list(frame_rows(evaluator, frames))
    clims = field_ranges(evaluator, drawn)
    if colour_range is not None:
        clims["sigma_n"] = (float(colour_range[0]), float(colour_range[1]))
    record["colour_range"] = {name: list(clim) for name, clim in clims.items()}
    record["seconds"]["colour_range"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    snapshots = render_snapshots(evaluator, out, instants, size, clims["sigma_n"], clims.get("tau"))
    record["files"] += [str(p) for p in snapshots]
    record["seconds"]["snapshots"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    record["files"].append(str(render_trajectory(evaluator, out / "trajectory.png", clim=clims["sigma_n"])))
    record["seconds"]["trajectory"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    record["files"].append(
        str(plot_histories(evaluator.history, evaluator.prepared, out / "resistance_centre.png", instants))
    )
    record["files"].append(str(plot_polar(evaluator, instants, out / "polar.png", station)))
    record["seconds"]["field_plots"] = time.perf_counter() - t0
    if animation:
        movie = render_animation(
            evaluator, out / "animation.gif", frames, clim=clims["sigma_n"], tau_clim=clims.get("tau")
        )
        record["files"].append(movie["path"])
        record["seconds"]["animation"] = movie["seconds"]
    if paraview:
        t0 = time.perf_counter()
        written = write_paraview(evaluator, out / "paraview", steps)
        record["files"].append(str(written["index"]))
        record["paraview_steps"] = len(written["surfaces"])
        record["seconds"]["paraview"] = time.perf_counter() - t0
    record["seconds"]["total"] = time.perf_counter() - start
    return record
