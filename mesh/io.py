"""Read and write projectile meshes with meshio, and a disk cache keyed by parameters.

Meshes are stored as VTK unstructured grids (``.vtu``): ParaView opens them,
and the cell data ``region`` holds :data:`~mesh.geometry.BODY`,
:data:`~mesh.geometry.COUNTERWEIGHT` or :data:`~mesh.geometry.OUTER`.
"""

from __future__ import annotations

import dataclasses
import hashlib
import importlib.metadata
import json
import os
import tempfile
from pathlib import Path

import numpy as np

from .geometry import OUTER, ProjectileMesh, build_mesh
from .profile import ProjectileGeometry

__all__ = ["write_mesh", "read_mesh", "cached_mesh", "mesh_key", "cache_dir"]

# bump when the meshing changes in a way that alters meshes of equal parameters
MESH_FORMAT_VERSION = 1

_CELL_TYPES = {1: ("tetra", "triangle"), 2: ("tetra10", "triangle6")}


def write_mesh(mesh: ProjectileMesh, path: str | os.PathLike) -> None:
    """Write a mesh atomically (to a temporary file renamed into place)."""
    path = Path(path)
    tet_type, tri_type = _CELL_TYPES[mesh.order]
    import meshio  # imported where used: a run from cached data never needs it

    out = meshio.Mesh(
        mesh.points,
        [(tet_type, mesh.tetra), (tri_type, mesh.outer)],
        cell_data={"region": [mesh.tetra_region.astype(np.int32),
                              np.full(len(mesh.outer), OUTER, dtype=np.int32)]},
    )
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=path.stem + ".", suffix=path.suffix)
    os.close(fd)
    try:
        meshio.write(tmp, out)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def read_mesh(path: str | os.PathLike) -> ProjectileMesh:
    """Read a mesh written by :func:`write_mesh`."""
    import meshio

    m = meshio.read(path)
    for order, (tet_type, tri_type) in _CELL_TYPES.items():
        if tet_type in m.cells_dict:
            regions = m.cell_data_dict["region"]
            return ProjectileMesh(
                points=np.asarray(m.points, dtype=float),
                tetra=m.cells_dict[tet_type].astype(np.int64),
                tetra_region=regions[tet_type].astype(np.int64),
                outer=m.cells_dict[tri_type].astype(np.int64),
                order=order,
            )
    raise ValueError(f"{path}: no tetrahedra found")


def cache_dir() -> Path:
    """The mesh cache folder: ``$PENETRATE_CACHE_DIR`` or ``~/.cache/penetrate/meshes``."""
    root = os.environ.get("PENETRATE_CACHE_DIR")
    return Path(root) if root else Path.home() / ".cache" / "penetrate" / "meshes"


def mesh_key(geometry: ProjectileGeometry, size: float, order: int) -> str:
    """A digest of everything that determines a mesh."""
    record = {
        "geometry": dataclasses.asdict(geometry),
        "nose": type(geometry.profile.nose).__name__,
        "size": size,
        "order": order,
        "gmsh": importlib.metadata.version("gmsh"),  # without importing gmsh (slow)
        "format": MESH_FORMAT_VERSION,
    }
    text = json.dumps(record, sort_keys=True, default=repr)
    return hashlib.sha256(text.encode()).hexdigest()[:24]


def cached_mesh(geometry: ProjectileGeometry, size: float, order: int = 2,
                directory: str | os.PathLike | None = None) -> ProjectileMesh:
    """The mesh of ``geometry``, from the disk cache when it was made before.

    A sweep therefore meshes each projectile once.  Writes are atomic, so
    concurrent workers at worst mesh the same projectile twice.
    """
    folder = Path(directory) if directory is not None else cache_dir()
    path = folder / f"{mesh_key(geometry, size, order)}.vtu"
    if path.exists():
        try:
            return read_mesh(path)
        except Exception:
            path.unlink(missing_ok=True)  # a corrupt entry: mesh again
    mesh = build_mesh(geometry, size, order)
    write_mesh(mesh, path)
    return mesh
