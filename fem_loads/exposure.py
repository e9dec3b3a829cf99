"""Which surface the target can reach: each quadrature point's exposure to the soil, by the direction of motion.

The DAFL loads every point whose normal velocity is positive.  On a body that is not convex that includes
surface the soil cannot reach: the inner wall of a base recess, the faces of a groove behind a shoulder,
fins in the lee of the body.  The body ahead of such a point has already opened the cavity it moves
through.  The criterion used here: the soil moves past the body against the body's velocity ``V`` (its
centre of mass's, in the body frame); a point meets it only if the ray from the point along ``V`` leaves
the body without hitting it.  Its *exposure* ``e`` is 1 then and 0 otherwise, and its stresses (normal
and friction) are multiplied by ``e``.  The direction is the body's, one for every point: a rotating body's
points move in directions up to ``asin(|omega| r_max / |V|)`` away from it (a few degrees in a turning run,
about one cell of the table below), which this leaves out.

Computed once per body, from the geometry (:func:`exposure_table`), and kept with the quadrature:

* a point on the body's convex hull (its tangent plane has the whole body on one side) is exposed in
  every direction that gives it a positive ``Vn``: such a ray leaves the tangent plane's half-space at
  once and never meets the body.  It needs no table, and a convex body (every body of revolution of
  the paper, a nose cut by a plane) has none at all;
* every other point gets ``e`` at the nodes of a cube map of directions, ``resolution`` cells along each
  face's edge: a ray cast against the outer surface (its curved facets split in four flat triangles)
  from the point, lifted off the surface by a fraction of the element size;
* within a cell's width of grazing, ``-sin(delta) < d . n <= 0`` (``delta`` the largest angular diameter of
  a cell), the ray goes along the tangential part of ``d``: a surface that slides along the body's path (a
  recess's wall at a small attack angle) is as hidden as its neighbours that advance, and ``e`` is
  continuous across ``Vn = 0``;
* a direction further back, ``d . n <= -sin(delta)``, recedes from the soil: ``e = 1`` there (its stress,
  where the contact model gives it any, is a receding surface's, which no shadow changes);
* between the nodes ``e`` is interpolated bilinearly on the face: a number in [0, 1], continuous in the
  direction, so that an adaptive step sees no jump when a shadow's edge crosses a point; a cell whose four
  nodes agree gives their value exactly.

The rays are traced by Embree (through trimesh).  For the compiled kernel each cell of the cube map also lists
the points hidden at one of its corners (:attr:`Exposure.cell_rows`): an evaluation visits only the points
hidden around the body's direction, and corrects those that carry stress (a few dozen in a forward run of
the finned body).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

__all__ = ["Exposure", "exposure_table", "cube_nodes", "cube_cell_scalars", "cell_diameter", "DEFAULT_RESOLUTION"]

#: cells along each edge of a cube face: 16 gives 6 x 17 x 17 directions, about 5.6 degrees apart
DEFAULT_RESOLUTION = 16


@dataclass(frozen=True)
class Exposure:
    """The exposure tables of the points that can be hidden.

    Attributes
    ----------
    columns : ndarray of int, shape (c,)
        The points that can be hidden, as columns of the loads' layout: positions in the fundamental
        part's points (``SurfaceQuadrature.mirror_images[0]``) of a mirror-symmetric quadrature, else
        point indices.  Every other point is exposed whenever its ``Vn`` is positive.
    table : ndarray of uint8, shape (c, 6, N + 1, N + 1)
        1 where the ray from the point along the node's direction (:func:`cube_nodes`) leaves the body.
    cell_start, cell_rows, cell_corners : ndarray
        The table by cell, for the compiled kernel: the rows (positions in :attr:`columns`) hidden at some
        corner of cell ``k`` (its flat index over ``(6, N, N)``) are ``cell_rows[cell_start[k]:cell_start[k + 1]]``,
        and ``cell_corners`` holds which corners, a bit each, in the order ``(i, j)``, ``(i + 1, j)``,
        ``(i, j + 1)``, ``(i + 1, j + 1)``.
    """

    columns: np.ndarray
    table: np.ndarray
    cell_start: np.ndarray = field(init=False)
    cell_rows: np.ndarray = field(init=False)
    cell_corners: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        hidden = self.table == 0
        corners = (hidden[:, :, :-1, :-1], hidden[:, :, 1:, :-1], hidden[:, :, :-1, 1:], hidden[:, :, 1:, 1:])
        bits = sum(corner.astype(np.uint8) << bit for bit, corner in enumerate(corners))  # (c, 6, N, N)
        flat = np.asarray(bits).reshape(len(self.table), -1)
        cell, row = np.nonzero(flat.T)  # cell-major: each cell's rows in order
        start = np.searchsorted(cell, np.arange(flat.shape[1] + 1))
        object.__setattr__(self, "cell_start", start.astype(np.int64))
        object.__setattr__(self, "cell_rows", row.astype(np.int64))
        object.__setattr__(self, "cell_corners", flat.T[cell, row].astype(np.int64))

    @property
    def resolution(self) -> int:
        return int(self.table.shape[-1]) - 1

    def hidden(self, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rows (positions in :attr:`columns`) not wholly exposed in one direction (body frame, any length, not
        zero), and their exposure there: :meth:`factor`'s values below 1, from the direction's cell's list (the
        other rows are exposed, 1)."""
        n = self.resolution
        face, i, j, fx, fy = cube_cell_scalars(n, float(direction[0]), float(direction[1]), float(direction[2]))
        cell = (face * n + i) * n + j
        span = slice(self.cell_start[cell], self.cell_start[cell + 1])
        masks = self.cell_corners[span]
        shares = np.array([(1.0 - fx) * (1.0 - fy), fx * (1.0 - fy), (1.0 - fx) * fy, fx * fy])
        bits = (masks[:, None] >> np.arange(4)) & 1
        exposure = np.where(masks == 15, 0.0, 1.0 - bits @ shares)
        return self.cell_rows[span], exposure

    def factor(self, directions: np.ndarray) -> np.ndarray:
        """``e`` of each point of :attr:`columns` for directions (body frame, any length), shape (..., c, 3);
        the result has shape (..., c): the table interpolated densely, every row at once (the loads use
        :meth:`hidden`'s few rows; this is the form they are checked against)."""
        n = self.resolution
        magnitude = np.abs(directions)
        axis = np.argmax(magnitude, axis=-1)
        major = np.take_along_axis(directions, axis[..., None], axis=-1)[..., 0]
        face = 2 * axis + (major < 0.0)
        scale = np.where(major != 0.0, 1.0 / np.where(major != 0.0, np.abs(major), 1.0), 0.0)
        s = np.take_along_axis(directions, ((axis + 1) % 3)[..., None], axis=-1)[..., 0] * scale
        t = np.take_along_axis(directions, ((axis + 2) % 3)[..., None], axis=-1)[..., 0] * scale
        x, y = (s + 1.0) * (0.5 * n), (t + 1.0) * (0.5 * n)
        i, j = np.clip(np.floor(x).astype(np.int64), 0, n - 1), np.clip(np.floor(y).astype(np.int64), 0, n - 1)
        fx, fy = x - i, y - j
        rows = np.broadcast_to(np.arange(len(self.columns)), face.shape)
        table = self.table
        a, b = table[rows, face, i, j], table[rows, face, i + 1, j]
        c, d = table[rows, face, i, j + 1], table[rows, face, i + 1, j + 1]
        value = (1.0 - fx) * (1.0 - fy) * a + fx * (1.0 - fy) * b + (1.0 - fx) * fy * c + fx * fy * d
        # a cell wholly hidden or wholly exposed is exactly 0 or 1, not 1 - 1e-16; no direction, no shadow
        return np.where(major == 0.0, 1.0, np.where((a == b) & (b == c) & (c == d), a, value))


def cube_cell_scalars(n: int, d0: float, d1: float, d2: float) -> tuple[int, int, int, float, float]:
    """The cube map's cell of a direction (any length, not zero), ``n`` cells along a face's edge: ``(face, i, j,
    fx, fy)``, the cell's first node (:func:`cube_nodes`) and the direction's place in it, in [0, 1] each.  The one
    definition: :meth:`Exposure.hidden` calls it and the compiled kernel compiles it (:mod:`fem_loads.native`)."""
    a0, a1, a2 = abs(d0), abs(d1), abs(d2)
    if a0 >= a1 and a0 >= a2:
        face, major, s, t = (0 if d0 >= 0.0 else 1), a0, d1, d2
    elif a1 >= a2:
        face, major, s, t = (2 if d1 >= 0.0 else 3), a1, d2, d0
    else:
        face, major, s, t = (4 if d2 >= 0.0 else 5), a2, d0, d1
    x, y = (s / major + 1.0) * (0.5 * n), (t / major + 1.0) * (0.5 * n)
    i, j = min(max(int(math.floor(x)), 0), n - 1), min(max(int(math.floor(y)), 0), n - 1)
    return face, i, j, x - i, y - j


def cube_nodes(resolution: int) -> np.ndarray:
    """The unit directions at the nodes of the cube map, shape (6, N + 1, N + 1, 3).

    Face ``f`` is the side of the cube along axis ``f // 2`` (positive for even ``f``); node ``(i, j)`` of
    it is the direction ``(+-1, s, t)`` in the axes ``(a, a + 1, a + 2)`` (mod 3), with ``s = 2 i / N - 1``
    and ``t = 2 j / N - 1``, normalised.  :meth:`Exposure.factor` inverts this.
    """
    grid = 2.0 * np.arange(resolution + 1) / resolution - 1.0
    s, t = np.meshgrid(grid, grid, indexing="ij")
    nodes = np.zeros((6, resolution + 1, resolution + 1, 3))
    for face in range(6):
        axis, sign = face // 2, -1.0 if face % 2 else 1.0
        nodes[face, :, :, axis] = sign
        nodes[face, :, :, (axis + 1) % 3] = s
        nodes[face, :, :, (axis + 2) % 3] = t
    return nodes / np.linalg.norm(nodes, axis=-1, keepdims=True)


def _on_hull(points: np.ndarray, normals: np.ndarray, nodes: np.ndarray, tolerance: float) -> np.ndarray:
    """Whether each point's tangent plane has every node of the body on its inner side (within ``tolerance``)."""
    from scipy.spatial import ConvexHull

    corners = nodes[ConvexHull(nodes).vertices]
    support = np.empty(len(points))
    for start in range(0, len(points), 4096):  # (points x hull corners) in blocks
        block = slice(start, start + 4096)
        support[block] = (normals[block] @ corners.T).max(axis=1)
    return support - np.einsum("ij,ij->i", normals, points) <= tolerance


def exposure_table(
    points: np.ndarray,
    normals: np.ndarray,
    triangles: np.ndarray,
    lift: float,
    resolution: int = DEFAULT_RESOLUTION,
) -> tuple[np.ndarray, np.ndarray]:
    """Which points can be hidden, and their tables (see the module).

    Parameters
    ----------
    points, normals : ndarray, shape (m, 3)
        The points to test (the fundamental part of a mirror-symmetric quadrature, else every point) and
        their outward unit normals, in the frame of ``triangles``.
    triangles : ndarray, shape (t, 3, 3)
        The outer surface as flat triangles (corners), the whole body.
    lift : float
        How far off the surface a ray starts (m): more than the flat triangles' distance from the exact
        surface the points lie on, so that a point does not hide itself.
    resolution : int
        Cells along each edge of a cube face.

    Returns
    -------
    columns : ndarray of int, shape (c,)
        The points hidden in some direction.
    table : ndarray of uint8, shape (c, 6, N + 1, N + 1)
        Their exposure at the cube map's nodes.
    """
    corners = triangles.reshape(-1, 3)
    candidates = np.flatnonzero(~_on_hull(points, normals, corners, lift))
    directions = cube_nodes(resolution).reshape(-1, 3)
    if len(candidates) == 0:
        return candidates, np.zeros((0, 6, resolution + 1, resolution + 1), dtype=np.uint8)
    # imported only for a body that is not convex (a second and more of the first preparation otherwise)
    import trimesh
    from trimesh.ray.ray_pyembree import RayMeshIntersector

    surface = trimesh.Trimesh(corners, np.arange(len(corners)).reshape(-1, 3), process=False)
    tracer = RayMeshIntersector(surface)
    grazing = math.sin(cell_diameter(resolution))
    table = np.ones((len(candidates), len(directions)), dtype=np.uint8)
    for row, point in enumerate(candidates):
        normal = normals[point]
        along = directions @ normal
        traced = np.flatnonzero(along > -grazing)  # advancing into the soil, or sliding along it
        rays = directions[traced]
        sliding = along[traced] <= 0.0
        rays[sliding] -= along[traced][sliding, None] * normal  # along the surface
        length = np.linalg.norm(rays, axis=1)
        rays[length < 1e-9] = _any_tangent(normal)
        origin = np.broadcast_to(points[point] + lift * normal, rays.shape)
        table[row, traced] = ~tracer.intersects_any(origin, rays)  # type: ignore[no-untyped-call]  # trimesh is untyped
    exposed_always = table.all(axis=1)
    keep = ~exposed_always
    shape = (-1, 6, resolution + 1, resolution + 1)
    return candidates[keep], np.ascontiguousarray(table[keep].reshape(shape))


def cell_diameter(resolution: int) -> float:
    """The largest angle (rad) between two corners of a cell of the cube map: a direction in a cell is within it
    of each of the cell's corners."""
    nodes = cube_nodes(resolution)
    first, last = nodes[:, :-1, :-1], nodes[:, 1:, 1:]
    across, other = nodes[:, 1:, :-1], nodes[:, :-1, 1:]
    cosine = min(np.einsum("fijd,fijd->fij", first, last).min(), np.einsum("fijd,fijd->fij", across, other).min())
    return float(np.arccos(np.clip(cosine, -1.0, 1.0)))


def _any_tangent(normal: np.ndarray) -> np.ndarray:
    """A unit vector perpendicular to ``normal``."""
    helper = np.eye(3)[int(np.argmin(np.abs(normal)))]
    tangent = np.cross(normal, helper)
    return tangent / np.linalg.norm(tangent)
