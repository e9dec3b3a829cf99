"""A projectile's mesh from a file: CAD files meshed by gmsh (:mod:`mesh.cad`), volume meshes read by meshio
(:mod:`mesh.volume_mesh`), and the checks every such mesh passes."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from .cad import cad_mesh, place_cad
from .geometry import TET_EDGES, ProjectileMesh
from .imported import FileGeometry, GeometryError
from .volume_mesh import place_volume_mesh, read_volume_mesh

__all__ = ["build_file_mesh", "place_file_body", "tangled"]


def place_file_body(geometry: FileGeometry) -> FileGeometry:
    """``geometry`` with the axis and origin its body gives (:func:`~mesh.imported.place`); as it is when placed.

    Raises
    ------
    GeometryError
        No such file, or one that cannot be read; an axis that cannot be found, or that the scene does not
        give where the body needs it.
    """
    if geometry.placed:
        return geometry
    if not Path(geometry.path).is_file():
        raise GeometryError(f"projectile.geometry.file = {geometry.path!r}: no such file")
    return place_cad(geometry) if geometry.is_cad else place_volume_mesh(geometry)


def build_file_mesh(geometry: FileGeometry, size: float, order: int = 2) -> ProjectileMesh:
    """Mesh (a CAD file) or read (a mesh file) the projectile of ``geometry``, in its model frame (placed
    first by :func:`place_file_body` when it is not).

    Raises
    ------
    GeometryError
        An unreadable file, no closed solid, several disjoint bodies, no tetrahedra,
        a body too large or small for its unit, a named material the file lacks.
    """
    geometry = place_file_body(geometry)
    mesh = cad_mesh(geometry, size, order) if geometry.is_cad else read_volume_mesh(geometry)
    extent = float(np.ptp(mesh.points, axis=0).max())
    folded = tangled(mesh)
    if folded.any():
        where = mesh.points[mesh.tetra[folded, 0]]
        fix = (
            "numerics.geometry_order = 1 (straight-sided tetrahedra, which cannot fold)"
            if geometry.is_cad
            else "untangle it (gmsh: Mesh.HighOrderOptimize = 2) or give 4-node tetrahedra"
        )
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: {int(folded.sum())} curved"
            f" tetrahedra fold over (their Jacobian changes sign; the first at x = "
            f"{where[0, 0]:.4g} m along the axis): {fix}"
        )
    if not size < extent:
        raise GeometryError(
            f"numerics.mesh_size = {size:g}: must be less than the body's largest extent, {extent:.4g} m"
        )
    return mesh


# barycentric points where a quadratic tetrahedron's Jacobian is sampled: corners, edge midpoints, centroid
_SAMPLES = np.vstack(
    [np.eye(4), 0.5 * (np.eye(4)[[0, 1, 0, 0, 1, 2]] + np.eye(4)[[1, 2, 2, 3, 3, 3]]), np.full((1, 4), 0.25)]
)


def tangled(mesh: ProjectileMesh) -> np.ndarray:
    """Which quadratic tetrahedra fold over: their Jacobian is not positive at a corner, an edge midpoint
    or the centroid (a straight-sided tetrahedron of positive volume never does)."""
    if mesh.order == 1:
        return np.zeros(len(mesh.tetra), dtype=bool)
    gradient = np.vstack([-np.ones((1, 3)), np.eye(3)])  # d(barycentric)/d(reference coordinates)
    x = mesh.points[mesh.tetra]  # (n, 10, 3)
    worst = np.full(len(mesh.tetra), np.inf)
    for b in _SAMPLES:
        # quadratic Lagrange shape functions' gradients: corners (4 L_i - 1) grad L_i, edges 4 (L_j grad L_i
        # + L_i grad L_j)
        d = [(4.0 * b[i] - 1.0) * gradient[i] for i in range(4)]
        d += [4.0 * (b[j] * gradient[i] + b[i] * gradient[j]) for i, j in TET_EDGES]
        jacobian = np.einsum("nkd,ke->nde", x, np.array(d))
        worst = np.minimum(worst, np.linalg.det(jacobian))
    return ~(worst > 0.0)
