"""Volume meshes of tetrahedra (first or second order) in any format meshio reads: ``.msh``, ``.vtu``, ``.inp``, ...

A mesh carries its own order and its own normals (no exact surface).  Its
materials are its physical groups (gmsh) or the values of a cell-data field the
scene names.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

import numpy as np

from .geometry import TET_EDGES, TRI_EDGES, ProjectileMesh, _orient_tetra, standard_output_discarded
from .imported import (
    TET_FACES,
    FileGeometry,
    GeometryError,
    check_size,
    components,
    face_table,
    model_frame,
    orient_by_volume,
    place,
    regions,
)

if TYPE_CHECKING:
    import meshio  # slow to import: at run time only where a file is read

__all__ = ["read_volume_mesh", "place_volume_mesh"]


def _boundary_faces(tetra: np.ndarray) -> np.ndarray:
    """The faces of a tetrahedral mesh that belong to one tetrahedron only, with their edge nodes."""
    keys, corners, _ = face_table(tetra)
    _, index, counts = np.unique(keys, axis=0, return_index=True, return_counts=True)
    single = np.sort(index[counts == 1])
    tris = corners[single]
    if tetra.shape[1] == 10:  # the edge nodes of each face, from its tetrahedron's
        local = np.array([f[:3] for f in TET_FACES])[single % 4]
        edge_of = {frozenset(e): 4 + k for k, e in enumerate(TET_EDGES)}
        owner = tetra[single // 4]
        cols = np.array([[edge_of[frozenset((f[i], f[j]))] for i, j in TRI_EDGES] for f in local])
        tris = np.column_stack([tris, np.take_along_axis(owner, cols, axis=1)])
    return tris


def place_volume_mesh(geometry: FileGeometry) -> FileGeometry:
    """``geometry`` with its axis and origin found from the mesh's body (:func:`~mesh.imported.place`): the
    centroid and inertia of its straight-sided tetrahedra, its ends from its nodes."""
    points, tetra, _, _ = _read(geometry)
    corners = points[tetra[:, :4]]  # (n, 4, 3)
    edges = corners[:, 1:] - corners[:, :1]
    volume = np.abs(np.linalg.det(edges)) / 6.0
    centroid = volume @ corners.mean(axis=1) / volume.sum()
    # second moments of each tetrahedron about the centroid: V/20 (sum r_i r_i^T + (sum r_i)(sum r_i)^T)
    r = corners - centroid
    total = r.sum(axis=1)
    second = np.einsum(
        "n,nij->ij", volume / 20.0, np.einsum("nki,nkj->nij", r, r) + np.einsum("ni,nj->nij", total, total)
    )
    inertia = np.trace(second) * np.eye(3) - second
    used = points[np.unique(tetra)]

    def span(direction: np.ndarray) -> tuple[float, float]:
        along = used @ direction
        return float(along.min()), float(along.max())

    return place(geometry, centroid, inertia, span)


def _read(geometry: FileGeometry) -> tuple[np.ndarray, np.ndarray, list[int], meshio.Mesh]:
    """The file's points (its coordinates and unit), its tetrahedra, the indices of their cell blocks and the
    mesh meshio read."""
    import meshio

    try:
        with standard_output_discarded():  # meshio prints an empty line reading a gmsh 4 file: stdout is the caller's
            m = meshio.read(geometry.path)
    except Exception as exc:  # meshio raises ReadError, KeyError, ValueError, ... on files it cannot parse
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: meshio cannot read it ({type(exc).__name__}: {exc})"
        ) from None
    blocks = [(k, b) for k, b in enumerate(m.cells) if b.type in ("tetra", "tetra10")]
    kinds = {b.type for _, b in blocks}
    if not blocks:
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: no tetrahedra (a volume mesh of"
            f" 4- or 10-node tetrahedra is needed; the file has {sorted({b.type for b in m.cells})})"
        )
    if len(kinds) > 1:
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: mixes 4- and 10-node tetrahedra; give one order"
        )
    tetra = np.concatenate([b.data for _, b in blocks]).astype(np.int64)
    points = np.asarray(m.points, dtype=float)
    if points.ndim != 2 or points.shape[1] != 3:
        raise GeometryError(f"projectile.geometry.file = {geometry.path!r}: the points are not 3-D")
    if tetra.size and (tetra.min() < 0 or tetra.max() >= len(points)):
        raise GeometryError(f"projectile.geometry.file = {geometry.path!r}: a tetrahedron names a point it lacks")
    return points, tetra, [k for k, _ in blocks], m


def read_volume_mesh(geometry: FileGeometry) -> ProjectileMesh:
    """The body of a volume mesh file in its model frame (``geometry`` placed)."""
    points, tetra, block_indices, m = _read(geometry)
    order = 2 if tetra.shape[1] == 10 else 1
    names = _mesh_region_names(geometry, m, block_indices)
    region_of = regions(geometry, {n: n for n in set(names.tolist())})
    region = np.array([region_of[n] for n in names.tolist()], dtype=np.int64)
    used, index = np.unique(tetra, return_inverse=True)
    tetra = index.reshape(tetra.shape)
    points = model_frame(points[used], geometry)
    check_size(float(np.ptp(points, axis=0).max()), geometry)
    # one body: every tetrahedron reachable from every other through shared faces
    keys, _, _ = face_table(tetra)
    _, inverse = np.unique(keys, axis=0, return_inverse=True)
    face_owner = np.repeat(np.arange(len(tetra)), 4)
    order_faces = np.argsort(inverse, kind="stable")
    same = inverse[order_faces][1:] == inverse[order_faces][:-1]
    pairs = list(zip(face_owner[order_faces][:-1][same].tolist(), face_owner[order_faces][1:][same].tolist()))
    n = len(set(components(len(tetra), pairs).tolist()))
    if n > 1:
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: {n} disjoint bodies; a projectile is one body"
        )
    tetra = _orient_tetra(points, tetra)
    faces = _boundary_faces(tetra)
    # keep the outermost shell: the boundary faces connected (through shared corners) to the foremost node
    edges = np.concatenate([faces[:, [0, 1]], faces[:, [1, 2]]])
    shell = components(len(points), [tuple(e) for e in edges.tolist()])
    front = shell[np.argmax(points[:, 0])]
    faces = faces[shell[faces[:, 0]] == front]
    return ProjectileMesh(points, tetra, region, orient_by_volume(points, faces, tetra), order)


def _mesh_region_names(geometry: FileGeometry, m: meshio.Mesh, block_indices: list[int]) -> np.ndarray:
    """The material name of each tetrahedron: the scene's cell-data field, else the physical groups."""
    field = geometry.cell_field
    if field is not None:
        if field not in m.cell_data:
            raise GeometryError(
                f"projectile.geometry.cell_field = {field!r}: the mesh has no such cell data"
                f" (it has: {', '.join(sorted(m.cell_data)) or 'none'})"
            )
        values = np.concatenate([np.asarray(m.cell_data[field][k]).reshape(-1) for k in block_indices])
        return np.array([_label(v) for v in values.tolist()], dtype=object)
    if "gmsh:physical" in m.cell_data:
        tags = np.concatenate([np.asarray(m.cell_data["gmsh:physical"][k]) for k in block_indices])
        named = {int(v[0]): name for name, v in m.field_data.items() if len(v) > 1 and int(v[1]) == 3}
        return np.array([named.get(int(t), f"group{int(t)}") for t in tags.tolist()], dtype=object)
    n = sum(len(m.cells[k].data) for k in block_indices)
    return np.full(n, "body", dtype=object)


def _label(value: float | str) -> str:
    """A cell-data value as a material name: integers without a decimal point."""
    return str(int(value)) if float(value).is_integer() else str(value)
