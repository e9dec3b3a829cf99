"""ParaView files of a run: the surface field over time (one VTU per step, indexed by a PVD) and the path."""

from __future__ import annotations

import os
import xml.etree.ElementTree as ET
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from ..run import atomic_write_text
from ..run.persistence import atomic_path
from .field import FieldEvaluator, frame_rows

if TYPE_CHECKING:
    import meshio

__all__ = ["write_paraview", "PARAVIEW_INDEX", "TRAJECTORY_FIELDS"]

PARAVIEW_INDEX = "run.pvd"


def _write_vtu(path: Path, mesh: meshio.Mesh) -> None:
    """A meshio mesh written as VTU, atomically."""
    import meshio

    with atomic_path(path) as tmp:
        meshio.write(tmp, mesh, file_format="vtu", binary=True)


TRAJECTORY_FIELDS = {
    "time": "s",
    "speed": "m/s",
    "attack_angle": "deg",
    "total_attack_angle": "deg",
    "tip_depth": "m",
    "path_length": "m",
    "resistance_centre_from_tip": "m",
}


def write_paraview(evaluator: FieldEvaluator, out_dir: str | os.PathLike, steps: int | None = 100) -> dict:
    """ParaView files of the run: the surface field over time and the path.

    Writes, in ``out_dir``:

    * ``surface/surface_NNNNN.vtu``: the drawn surface at its true position and attitude (world
      frame, m) with cell data ``sigma_n`` (Pa), ``normal_velocity`` (m/s) and, with friction,
      ``tau`` (Pa), one file per written step;
    * ``trajectory.vtu``: the centre-of-mass path as line segments with point data
      :data:`TRAJECTORY_FIELDS` (every recorded step);
    * ``run.pvd``: the index: each step's surface (part 0) and the path (part 1) at its time, so
      opening this one file in ParaView plays the run.

    Parameters
    ----------
    steps : int or None
        Number of steps written, evenly spaced in time; None writes every recorded step.

    Returns
    -------
    dict
        ``index`` (path of run.pvd), ``surfaces`` (list of paths), ``trajectory``, ``times``, ``rows``.
    """
    import meshio

    out = Path(out_dir)
    (out / "surface").mkdir(parents=True, exist_ok=True)
    ev = evaluator
    rows = frame_rows(ev, steps)
    cells = [("triangle", ev.surface.triangles.astype(np.int64))]
    surfaces, times = [], []
    for n, row in enumerate(rows):
        fld = ev.at(int(row))
        data = {"sigma_n": [ev.cell_values(fld.sigma_n)], "normal_velocity": [ev.cell_values(fld.normal_velocity)]}
        if fld.tau is not None:
            data["tau"] = [ev.cell_values(fld.tau)]
        path = out / "surface" / f"surface_{n:05d}.vtu"
        _write_vtu(path, meshio.Mesh(ev.world_points(int(row)), cells, cell_data=data))
        surfaces.append(path)
        times.append(fld.time)
    positions = ev.result.trajectory.position
    n_points = len(positions)
    segments = (
        np.column_stack([np.arange(n_points - 1), np.arange(1, n_points)])
        if n_points > 1
        else np.zeros((0, 2), dtype=np.int64)
    )
    point_data = {name: ev.history[name].to_numpy(dtype=float) for name in TRAJECTORY_FIELDS}
    trajectory = out / "trajectory.vtu"
    _write_vtu(trajectory, meshio.Mesh(positions, [("line", segments)], point_data=point_data))
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    collection = ET.SubElement(root, "Collection")
    for path, t in zip(surfaces, times):
        ET.SubElement(
            collection, "DataSet", timestep=repr(float(t)), group="", part="0", file=path.relative_to(out).as_posix()
        )
        ET.SubElement(collection, "DataSet", timestep=repr(float(t)), group="", part="1", file=trajectory.name)
    ET.indent(root)
    index = out / PARAVIEW_INDEX
    atomic_write_text(index, '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n")
    return {
        "index": index,
        "surfaces": surfaces,
        "trajectory": trajectory,
        "times": times,
        "rows": [int(r) for r in rows],
    }
