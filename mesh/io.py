"""Read and write projectile meshes with meshio.

Meshes are stored as VTK unstructured grids (``.vtu``): ParaView opens them,
and the cell data ``region`` holds :data:`~mesh.geometry.BODY`,
:data:`~mesh.geometry.COUNTERWEIGHT` or :data:`~mesh.geometry.OUTER`.
Writing is plain; a caller that needs a file to appear whole (a cache shared
by concurrent processes) writes to a temporary path and renames it
(``cases.run.persistence``).
"""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from .geometry import OUTER, ProjectileMesh

__all__ = ["write_mesh", "read_mesh", "MESH_FORMAT"]

MESH_FORMAT = "vtu"
_CELL_TYPES = {1: ("tetra", "triangle"), 2: ("tetra10", "triangle6")}


def write_mesh(mesh: ProjectileMesh, path: str | os.PathLike[str]) -> None:
    """Write ``mesh`` to ``path`` as a VTK unstructured grid, whatever the file's suffix."""
    import meshio  # imported where used: a run from cached data never needs it

    tet_type, tri_type = _CELL_TYPES[mesh.order]
    cell_data = {"region": [mesh.tetra_region.astype(np.int32), np.full(len(mesh.outer), OUTER, dtype=np.int32)]}
    if mesh.outer_entity is not None:  # the CAD surface of each outer triangle
        cell_data["entity"] = [np.zeros(len(mesh.tetra), dtype=np.int32), mesh.outer_entity.astype(np.int32)]
    out = meshio.Mesh(mesh.points, [(tet_type, mesh.tetra), (tri_type, mesh.outer)], cell_data=cell_data)
    meshio.write(Path(path), out, file_format=MESH_FORMAT)


def read_mesh(path: str | os.PathLike[str]) -> ProjectileMesh:
    """Read a mesh written by :func:`write_mesh`."""
    import meshio

    m = meshio.read(path, file_format=MESH_FORMAT)
    for order, (tet_type, tri_type) in _CELL_TYPES.items():
        if tet_type in m.cells_dict:
            regions = m.cell_data_dict["region"]
            return ProjectileMesh(
                points=np.asarray(m.points, dtype=float),
                tetra=m.cells_dict[tet_type].astype(np.int64),
                tetra_region=regions[tet_type].astype(np.int64),
                outer=m.cells_dict[tri_type].astype(np.int64),
                order=order,
                outer_entity=(
                    m.cell_data_dict["entity"][tri_type].astype(np.int64) if "entity" in m.cell_data_dict else None
                ),
            )
    raise ValueError(f"{path}: no tetrahedra found")
