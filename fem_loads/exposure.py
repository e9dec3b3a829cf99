"""Which surface the target can reach: each quadrature point's exposure to the soil, by the direction of motion.

The criterion: the soil moves past the body against the body's velocity ``V`` (its centre of mass's, in the body
frame); a point meets it only if the ray from the point along ``V`` leaves the body without hitting it.  Its
*exposure* ``e`` is 1 then and 0 otherwise, and multiplies its stresses (normal and friction).

Computed once per body (:func:`exposure_table`) and kept with the quadrature (docs/geometry.md explains it,
docs/evidence-geometry.md measures it): no table for a point on the body's convex hull (a convex body has none);
for every other point ``e`` at the nodes of a cube map of directions (:func:`cube_nodes`), rays along the surface
within a cell's width of grazing (:func:`_exposed`), the cells whose nodes disagree refined (:data:`SUB_CELLS`),
and ``e`` bilinear between the (sub-)nodes: exactly 0 or 1 in a cell whose four nodes agree.

For the compiled kernel each cell also lists the points hidden at one of its corners (:attr:`Exposure.cell_rows`):
an evaluation visits only those around the body's direction.  :func:`cube_cell_scalars` and
:func:`cell_exposure_scalars` are the one definition of ``e``, for both.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Any  # the ray tracer's: trimesh is untyped

import numpy as np

__all__ = [
    "Exposure",
    "exposure_table",
    "cube_nodes",
    "cube_cell_scalars",
    "cell_exposure_scalars",
    "cell_diameter",
    "DEFAULT_RESOLUTION",
    "SUB_CELLS",
    "LIFT_FLOOR",
]

#: cells along each edge of a cube face: 16 gives 6 x 17 x 17 directions, about 5.6 degrees apart
DEFAULT_RESOLUTION = 16
#: sub-cells along each edge of a refined cell: (6 + 1)^2 = 49 sub-nodes, a bit each in an int64
SUB_CELLS = 6
#: the least lift of a ray's start, as a share of the largest (well above the ray tracer's round-off)
LIFT_FLOOR = 0.01
_BATCH = 64  # rows refined together
# the sub-node bits along each edge of a refined cell: a = 0, a = SUB_CELLS, b = 0, b = SUB_CELLS
_BITS = (1 << np.arange((SUB_CELLS + 1) ** 2, dtype=np.int64)).reshape(SUB_CELLS + 1, SUB_CELLS + 1)  # [b, a]
_EDGE_MASKS = np.array([edge.sum() for edge in (_BITS[:, 0], _BITS[:, -1], _BITS[0], _BITS[-1])])


@dataclass(frozen=True)
class Exposure:
    """The exposure tables of the points that can be hidden.

    Attributes
    ----------
    columns : ndarray of int, shape (c,)
        The points that can be hidden, as columns of the loads' layout: positions in the fundamental part's
        points (``SurfaceQuadrature.mirror_images[0]``) of a mirror-symmetric quadrature, else point indices.
    table : ndarray of uint8, shape (c, 6, N + 1, N + 1)
        1 where the ray from the point along the node's direction (:func:`cube_nodes`) leaves the body.
    refined : ndarray of int64, shape (r, 3)
        The refined cells: ``(row, cell, bits)``, the cell's flat index over ``(6, N, N)`` and its sub-nodes
        hidden, bit ``b (SUB_CELLS + 1) + a`` for the sub-node ``a / SUB_CELLS`` of the way from ``(i, j)``
        to ``(i + 1, j)`` and ``b / SUB_CELLS`` to ``(i, j + 1)``.  Empty: no cell refined.
    cell_start, cell_rows, cell_corners, cell_fine : ndarray
        The table by cell, for the compiled kernel: the rows (positions in :attr:`columns`) hidden at some
        corner of cell ``k`` (its flat index over ``(6, N, N)``) are ``cell_rows[cell_start[k]:cell_start[k + 1]]``,
        ``cell_corners`` holds which corners, a bit each, in the order ``(i, j)``, ``(i + 1, j)``,
        ``(i, j + 1)``, ``(i + 1, j + 1)``, and ``cell_fine`` the refined cell's sub-node bits (-1 where it is
        not refined).
    """

    columns: np.ndarray
    table: np.ndarray
    refined: np.ndarray = field(default_factory=lambda: np.zeros((0, 3), dtype=np.int64))
    cell_start: np.ndarray = field(init=False)
    cell_rows: np.ndarray = field(init=False)
    cell_corners: np.ndarray = field(init=False)
    cell_fine: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        hidden = self.table == 0
        corners = (hidden[:, :, :-1, :-1], hidden[:, :, 1:, :-1], hidden[:, :, :-1, 1:], hidden[:, :, 1:, 1:])
        bits = sum(corner.astype(np.uint8) << bit for bit, corner in enumerate(corners))  # (c, 6, N, N)
        flat = np.asarray(bits).reshape(len(self.table), -1)
        refined = np.asarray(self.refined, dtype=np.int64).reshape(-1, 3)
        listed = flat != 0
        listed[refined[:, 0], refined[:, 1]] = True  # a refined cell may be hidden inside, its corners not
        cell, row = np.nonzero(listed.T)  # cell-major: each cell's rows in order
        start = np.searchsorted(cell, np.arange(flat.shape[1] + 1))
        fine = np.full(len(cell), -1, dtype=np.int64)
        if len(refined):
            keys = cell * len(self.table) + row  # ascending: cell-major, rows in order
            fine[np.searchsorted(keys, refined[:, 1] * len(self.table) + refined[:, 0])] = refined[:, 2]
        object.__setattr__(self, "cell_start", start.astype(np.int64))
        object.__setattr__(self, "cell_rows", row.astype(np.int64))
        object.__setattr__(self, "cell_corners", flat.T[cell, row].astype(np.int64))
        object.__setattr__(self, "cell_fine", fine)

    @property
    def resolution(self) -> int:
        return int(self.table.shape[-1]) - 1

    def hidden(self, direction: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """The rows (positions in :attr:`columns`) listed in the cell of a direction (body frame, any length, not
        zero), and their exposure there; every other row's is 1."""
        n = self.resolution
        face, i, j, fx, fy = cube_cell_scalars(n, float(direction[0]), float(direction[1]), float(direction[2]))
        cell = (face * n + i) * n + j
        span = slice(self.cell_start[cell], self.cell_start[cell + 1])
        # cell_exposure_scalars on every row at once: the refined rows by their sub-nodes, the others by corners
        fine = self.cell_fine[span]
        exposure = corner_exposure(self.cell_corners[span], fx, fy)
        refined = fine >= 0
        if refined.any():
            exposure[refined] = fine_exposure(fine[refined], fx, fy)
        return self.cell_rows[span], exposure

    def factor(self, directions: np.ndarray) -> np.ndarray:
        """``e`` of each point of :attr:`columns` for directions (body frame, any length), shape (..., c, 3), as
        shape (..., c): :meth:`hidden` for every row (1 for no direction)."""
        directions = np.asarray(directions, dtype=float)
        value = np.ones(directions.shape[:-1])
        found: dict[bytes, dict[int, float]] = {}
        for index in np.ndindex(value.shape):
            direction = directions[index]
            if direction.any():
                key = direction.tobytes()
                if key not in found:
                    rows, exposure = self.hidden(direction)
                    found[key] = dict(zip(rows.tolist(), exposure.tolist()))
                value[index] = found[key].get(index[-1], 1.0)
        return value


def cube_cell_scalars(n: int, d0: float, d1: float, d2: float) -> tuple[int, int, int, float, float]:
    """The cube map's cell of a direction (any length, not zero), ``n`` cells along a face's edge: ``(face, i, j,
    fx, fy)``, the cell's first node (:func:`cube_nodes`) and the direction's place in it, in [0, 1] each."""
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


def cell_exposure_scalars(mask: int, fine: int, fx: float, fy: float) -> float:
    """``e`` at the place ``(fx, fy)`` in a cell (:func:`cube_cell_scalars`) of a point hidden at the corners
    ``mask`` (:attr:`Exposure.cell_corners`), with the sub-node bits ``fine`` of a refined cell (-1: not refined)."""
    return corner_exposure(mask, fx, fy) if fine < 0 else fine_exposure(fine, fx, fy)


def fine_exposure(bits: Any, fx: float, fy: float) -> Any:
    """``e`` at ``(fx, fy)`` in a refined cell (``bits`` an int, or an array of them): bilinear between the four
    hidden-or-not sub-nodes around it."""
    x, y = fx * SUB_CELLS, fy * SUB_CELLS
    a, b = min(max(int(math.floor(x)), 0), SUB_CELLS - 1), min(max(int(math.floor(y)), 0), SUB_CELLS - 1)
    first = b * (SUB_CELLS + 1) + a
    mask = ((bits >> first) & 1) | (((bits >> (first + 1)) & 1) << 1)
    mask |= (((bits >> (first + SUB_CELLS + 1)) & 1) << 2) | (((bits >> (first + SUB_CELLS + 2)) & 1) << 3)
    return corner_exposure(mask, x - a, y - b)


def corner_exposure(mask: Any, fx: float, fy: float) -> Any:
    """``e`` at ``(fx, fy)`` in a cell hidden at the corners ``mask`` (:attr:`Exposure.cell_corners`; an int, or an
    array of them for many points at one place): one less the bilinear shares of the hidden corners; 0 exactly at
    four.  Each share is multiplied by its corner's bit, not branched on, so that an array takes the same
    arithmetic (a share times 0 or 1 is exact)."""
    gx, gy = 1.0 - fx, 1.0 - fy
    exposure = 1.0 - (mask & 1) * (gx * gy)
    exposure -= ((mask >> 1) & 1) * (fx * gy)
    exposure -= ((mask >> 2) & 1) * (gx * fy)
    exposure -= ((mask >> 3) & 1) * (fx * fy)
    return exposure * (mask != 15)  # the four shares sum to 1 only up to rounding


def cube_nodes(resolution: int) -> np.ndarray:
    """The unit directions at the nodes of the cube map, shape (6, N + 1, N + 1, 3): node ``(i, j)`` of face ``f``
    at ``s = 2 i / N - 1``, ``t = 2 j / N - 1`` (:func:`_on_faces`); :func:`cube_cell_scalars` inverts this."""
    grid = 2.0 * np.arange(resolution + 1) / resolution - 1.0
    s, t = np.meshgrid(grid, grid, indexing="ij")
    shape = (6, resolution + 1, resolution + 1)
    return _on_faces(np.arange(6), np.broadcast_to(s, shape), np.broadcast_to(t, shape))


def _on_faces(faces: np.ndarray, s: np.ndarray, t: np.ndarray) -> np.ndarray:
    """The unit directions at ``(s, t)`` (shape (k, ...)) on faces ``faces`` (shape (k,)), shape (k, ..., 3): face
    ``f`` is the side of the cube along axis ``a = f // 2`` (positive for even ``f``), and ``(s, t)`` on it the
    direction ``(+-1, s, t)`` in the axes ``(a, a + 1, a + 2)`` (mod 3), normalised."""
    directions = np.empty((*s.shape, 3))
    for face in range(6):
        on = faces == face
        axis = face // 2
        directions[on, ..., axis] = -1.0 if face % 2 else 1.0
        directions[on, ..., (axis + 1) % 3] = s[on]
        directions[on, ..., (axis + 2) % 3] = t[on]
    return directions / np.linalg.norm(directions, axis=-1, keepdims=True)


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
    least_lift: float | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Which points can be hidden, their tables and their refined cells (see the module).

    Parameters
    ----------
    points, normals : ndarray, shape (m, 3)
        The points to test (the fundamental part of a mirror-symmetric quadrature, else every point) and
        their outward unit normals, in the frame of ``triangles``.
    triangles : ndarray, shape (t, 3, 3)
        The outer surface as flat triangles (corners), the whole body.
    lift : float
        The furthest off the surface a ray starts (m): more than the flat triangles' largest distance from the
        exact surface.  Each point's ray starts twice its own distance from them off it, at least ``least_lift``.
    resolution : int
        Cells along each edge of a cube face.
    least_lift : float, optional
        The least lift (m); ``LIFT_FLOOR * lift`` by default.  Give ``lift`` for a surface of flat facets, whose
        points lie on the triangles: every ray then starts beyond its facets' dents.

    Returns
    -------
    columns, table, refined : ndarray
        The points hidden in some direction, their exposure at the cube map's nodes and their refined cells:
        the fields of :class:`Exposure`.
    """
    corners = triangles.reshape(-1, 3)
    candidates = np.flatnonzero(~_on_hull(points, normals, corners, lift))
    shape = (-1, 6, resolution + 1, resolution + 1)
    if len(candidates) == 0:
        return candidates, np.zeros((0, *shape[1:]), dtype=np.uint8), np.zeros((0, 3), dtype=np.int64)
    import trimesh  # only for a body that is not convex
    from trimesh.ray.ray_pyembree import RayMeshIntersector

    tracer = RayMeshIntersector(trimesh.Trimesh(corners, np.arange(len(corners)).reshape(-1, 3), process=False))
    least = LIFT_FLOOR * lift if least_lift is None else least_lift
    lifts = np.clip(2.0 * _sag(tracer, points[candidates], normals[candidates], lift), least, lift)
    grazing = math.sin(cell_diameter(resolution))
    directions = cube_nodes(resolution).reshape(-1, 3)
    table = np.ones((len(candidates), len(directions)), dtype=np.uint8)
    for row, point in enumerate(candidates):
        table[row] = _exposed(tracer, points[point], normals[point], lifts[row], directions, grazing)
    keep = ~table.all(axis=1)
    table = np.ascontiguousarray(table[keep].reshape(shape))
    kept = candidates[keep]
    refined = [np.zeros((0, 3), dtype=np.int64)]
    for first in range(0, len(kept), _BATCH):  # rows in batches: (rows x refined cells x 49) rays at a time
        rows = slice(first, first + _BATCH)
        found = _refined(tracer, points[kept[rows]], normals[kept[rows]], lifts[keep][rows], table[rows], grazing)
        found[:, 0] += first
        refined.append(found)
    return kept, table, np.concatenate(refined)


def _exposed(
    tracer: Any, point: np.ndarray, normal: np.ndarray, lift: np.ndarray | float, directions: np.ndarray, grazing: float
) -> np.ndarray:
    """1 where the ray from ``point`` (lifted by ``lift`` along ``normal``) along each direction leaves the body:
    advancing ones as they are, those within ``grazing`` behind the tangent plane (``-grazing < d . n <= 0``) along
    the surface, so that ``e`` is continuous across ``Vn = 0``; receding ones exposed.  ``point``, ``normal`` and
    ``lift`` are one point's, or each direction's (shapes (r, 3), (r,))."""
    point, normal = np.broadcast_to(point, directions.shape), np.broadcast_to(normal, directions.shape)
    lift = np.broadcast_to(lift, directions.shape[:1])
    exposed = np.ones(len(directions), dtype=np.uint8)
    along = np.einsum("ij,ij->i", directions, normal)
    traced = np.flatnonzero(along > -grazing)  # advancing into the soil, or sliding along it
    rays, normal, along = directions[traced], normal[traced], along[traced]
    sliding = along <= 0.0
    rays[sliding] -= along[sliding, None] * normal[sliding]  # along the surface
    for k in np.flatnonzero(np.linalg.norm(rays, axis=1) < 1e-9):  # nothing left along the surface: any tangent
        tangent = np.cross(normal[k], np.eye(3)[int(np.argmin(np.abs(normal[k])))])
        rays[k] = tangent / np.linalg.norm(tangent)
    origin = point[traced] + lift[traced, None] * normal
    exposed[traced] = ~tracer.intersects_any(origin, rays)
    return exposed


def _refined(
    tracer: Any, points: np.ndarray, normals: np.ndarray, lifts: np.ndarray, table: np.ndarray, grazing: float
) -> np.ndarray:
    """``(row, cell, bits)`` of each cell of the rows' tables (shape (c, 6, N + 1, N + 1)) whose corners disagree,
    and of each cell next to a refined one across an edge whose sub-nodes disagree (so that ``e`` stays continuous
    from cell to cell on a face): its sub-nodes traced, a bit each where hidden (:attr:`Exposure.refined`)."""
    n = table.shape[-1] - 1
    total = table[..., :-1, :-1].astype(int) + table[..., 1:, :-1] + table[..., :-1, 1:] + table[..., 1:, 1:]
    chosen = (total > 0) & (total < 4)
    done = np.zeros_like(chosen)
    bits = np.zeros(chosen.shape, dtype=np.int64)
    while True:  # a refined cell's edge whose sub-nodes disagree refines the cell across it (on the same face)
        rows, faces, i, j = np.nonzero(chosen & ~done)
        if len(rows) == 0:
            break
        directions = _sub_nodes(n, faces, i, j)  # (k, 49, 3)
        nodes = directions.shape[1]
        each = np.repeat(rows, nodes)  # each sub-node's row
        hidden = 1 - _exposed(tracer, points[each], normals[each], lifts[each], directions.reshape(-1, 3), grazing)
        found = (hidden.reshape(-1, nodes).astype(np.int64) << np.arange(nodes, dtype=np.int64)).sum(axis=1)
        bits[rows, faces, i, j], done[rows, faces, i, j] = found, True
        for (di, dj), edge in zip(((-1, 0), (1, 0), (0, -1), (0, 1)), _EDGE_MASKS.tolist()):
            part = found & edge
            across = (part != 0) & (part != edge) & (i + di >= 0) & (i + di < n) & (j + dj >= 0) & (j + dj < n)
            chosen[rows[across], faces[across], i[across] + di, j[across] + dj] = True
    rows, cells = np.nonzero(done.reshape(len(done), -1))
    return np.column_stack([rows, cells, bits.reshape(len(bits), -1)[rows, cells]]).astype(np.int64).reshape(-1, 3)


def _sub_nodes(n: int, faces: np.ndarray, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """The unit directions of the sub-nodes of cells ``(faces, i, j)``, shape (k, (SUB_CELLS + 1)^2, 3): sub-node
    ``(a, b)`` at ``b (SUB_CELLS + 1) + a``."""
    sub = np.arange(SUB_CELLS + 1) / SUB_CELLS
    a, b = np.meshgrid(sub, sub, indexing="xy")
    s = 2.0 * (i[:, None] + a.ravel()[None, :]) / n - 1.0
    t = 2.0 * (j[:, None] + b.ravel()[None, :]) / n - 1.0
    return _on_faces(faces, s, t)


def _sag(tracer: Any, points: np.ndarray, normals: np.ndarray, lift: float) -> np.ndarray:
    """Each point's distance from the flat triangles along its normal, either way (0 where a ray finds them
    nowhere within ``lift``): how far its chord lies under or over it."""
    sag = np.full(len(points), np.inf)
    for side in (1.0, -1.0):
        rays = side * normals
        hits, ray, _ = tracer.intersects_location(points, rays, multiple_hits=False)
        distance = np.einsum("ij,ij->i", hits - points[ray], rays[ray])
        np.minimum.at(sag, ray, np.abs(distance))
    return np.where(sag <= lift, sag, 0.0)


def cell_diameter(resolution: int) -> float:
    """The largest angle (rad) between two corners of a cell of the cube map: a direction in a cell is within it
    of each of the cell's corners."""
    nodes = cube_nodes(resolution)
    diagonals = ((nodes[:, :-1, :-1], nodes[:, 1:, 1:]), (nodes[:, 1:, :-1], nodes[:, :-1, 1:]))
    cosine = min(np.einsum("fijd,fijd->fij", first, last).min() for first, last in diagonals)
    return float(np.arccos(np.clip(cosine, -1.0, 1.0)))
