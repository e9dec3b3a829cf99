"""Build and mesh a projectile with gmsh's OpenCASCADE kernel.

The half-profile is drawn in the x-y plane of the body frame (x forward, tip at
the origin, so a point ``s`` behind the tip has ``x = -s``) as exact circle arcs
and lines, split into a body face and a counterweight face, revolved by a
quarter turn about the x axis, and meshed with tetrahedra (first or second
order).  The quarter is then mirrored about the planes ``y = 0`` and ``z = 0``
in numpy, so the full mesh is exactly symmetric under both mirrors: a
symmetric scene then gives a symmetric load to round-off, which an
unstructured full mesh would not (its quadrature of ``cos(theta)`` around the
axis is not exactly zero, and an instability can grow from that seed).

Physical groups: volume ``body``, volume ``counterweight`` (when present) and
the outer surface ``outer``.
"""

from __future__ import annotations

import contextlib
import ctypes
import math
import os
import sys
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any

import numpy as np

from .profile import ProjectileGeometry

__all__ = [
    "ProjectileMesh",
    "build_mesh",
    "mirror_mesh",
    "outer_triangles",
    "MIRRORED_ENTITY",
    "BODY",
    "COUNTERWEIGHT",
    "OUTER",
]

# region tags stored with each cell of a ProjectileMesh
BODY, COUNTERWEIGHT, OUTER = 1, 2, 3

_GMSH_LOCK = threading.Lock()  # gmsh keeps global state: one model at a time per process

# corner pairs of the edge nodes of a 10-node tetrahedron, in scikit-fem's
# (and the order used throughout this package) local edge order
TET_EDGES = ((0, 1), (1, 2), (0, 2), (0, 3), (1, 3), (2, 3))
TRI_EDGES = ((0, 1), (1, 2), (0, 2))

# reads the elements of some gmsh entities (by tag) as rows of node indices (:func:`elements`)
ElementReader = Callable[[list[int]], np.ndarray]


@dataclass
class ProjectileMesh:
    """A tetrahedral projectile mesh in the body frame (tip at the origin, x forward).

    Attributes
    ----------
    points : ndarray, shape (n_points, 3)
        Node coordinates (m).
    tetra : ndarray, shape (n_tets, 4) or (n_tets, 10)
        Tetrahedra: 4 corners, then for second order the 6 edge nodes in the
        order of :data:`TET_EDGES`.  Positively oriented.
    tetra_region : ndarray, shape (n_tets,)
        :data:`BODY` or :data:`COUNTERWEIGHT` for each tetrahedron.
    outer : ndarray, shape (n_tris, 3) or (n_tris, 6)
        Triangles of the outer surface, oriented with outward normals
        (corners, then edge nodes in the order of :data:`TRI_EDGES`).
    order : int
        Geometry order: 1 (flat) or 2 (curved, quadratic).
    outer_entity : ndarray, shape (n_tris,), optional
        The CAD surface each outer triangle lies on (a file's projectile,
        :mod:`mesh.imported`); None for the analytic projectiles.
    """

    points: np.ndarray
    tetra: np.ndarray
    tetra_region: np.ndarray
    outer: np.ndarray
    order: int
    outer_entity: np.ndarray | None = None


def _edge_reorder(element_type: int, edges: tuple[tuple[int, int], ...]) -> np.ndarray:
    """Column order that turns gmsh's local node order into ours (corners, then ``edges``)."""
    import gmsh

    _, dim, _, n_nodes, local, n_corners = gmsh.model.mesh.getElementProperties(element_type)
    local = np.asarray(local).reshape(n_nodes, dim)
    order = list(range(n_corners))
    for i, j in edges:
        mid = 0.5 * (local[i] + local[j])
        order.append(int(np.argmin(np.linalg.norm(local - mid, axis=1))))
    return np.asarray(order)


def _profile_faces(occ: Any, geometry: ProjectileGeometry) -> tuple[list[int], list[int]]:
    """Draw the half-profile faces; return (body faces, counterweight faces)."""
    p = geometry.profile
    a, ln, length = p.radius, p.nose_length, p.length

    arc = p.arc()

    def nose_curve(tip_x: float, tip_r: float, drop: float) -> tuple[int, int, int]:
        """Nose curve of the profile lowered radially by ``drop``; returns (curve, tip pt, shoulder pt)."""
        tip = occ.addPoint(tip_x, tip_r, 0.0)
        shoulder = occ.addPoint(-ln, a - drop, 0.0)
        if p.curve is not None:  # a measured nose: its cubic pieces, exactly, as one B-spline
            poles, knots, multiplicities = p.curve.bezier(-tip_x, drop)
            inner = [occ.addPoint(-s, r, 0.0) for s, r in poles[1:-1]]
            curve = occ.addBSpline([tip, *inner, shoulder], degree=3, knots=knots, multiplicities=multiplicities)
            occ.remove([(0, t) for t in inner])
        elif arc is not None:
            s_c, r_c, _ = arc
            centre = occ.addPoint(-s_c, r_c - drop, 0.0)
            curve = occ.addCircleArc(tip, centre, shoulder)
            occ.remove([(0, centre)])
        else:
            curve = occ.addLine(tip, shoulder)
        return curve, tip, shoulder

    def body_curves(shoulder: int, drop: float, end_x: float) -> tuple[list[int], int]:
        """The shank (and a measured body, exactly, as one B-spline) from the shoulder to ``end_x``, lowered by
        ``drop``; returns (curves, the corner point at ``end_x``)."""
        end = -end_x
        corner = occ.addPoint(end_x, float(p.radius_at(end)) - drop, 0.0)
        if p.body is None or end <= p.body.start:
            return [occ.addLine(shoulder, corner)], corner
        assert p.body_curve is not None  # a body has its curve
        poles, knots, multiplicities = p.body_curve.bezier(p.body.start, drop, end)
        start = occ.addPoint(-p.body.start, a - drop, 0.0)
        inner = [occ.addPoint(-s, r, 0.0) for s, r in poles[1:-1]]
        curve = occ.addBSpline([start, *inner, corner], degree=3, knots=knots, multiplicities=multiplicities)
        occ.remove([(0, t) for t in inner])
        curves = [curve] if p.body.start <= ln else [occ.addLine(shoulder, start), curve]
        return curves, corner

    def closed_face(tip_x: float, tip_r: float, drop: float, end_x: float) -> int:
        curve, tip, shoulder = nose_curve(tip_x, tip_r, drop)
        shank, corner = body_curves(shoulder, drop, end_x)
        axis_end = occ.addPoint(end_x, 0.0, 0.0)
        curves = [curve, *shank, occ.addLine(corner, axis_end)]
        if tip_r > 0.0:  # a flat front face
            axis_tip = occ.addPoint(tip_x, 0.0, 0.0)
            curves += [occ.addLine(axis_end, axis_tip), occ.addLine(axis_tip, tip)]
        else:
            curves.append(occ.addLine(axis_end, tip))
        return occ.addPlaneSurface([occ.addCurveLoop(curves)])

    outer = closed_face(0.0, p.tip_radius, 0.0, -length)
    if geometry.interior is None:
        return [outer], []
    cavity = closed_face(-geometry.cavity_start, 0.0, geometry.interior.wall_thickness, -geometry.cavity_end)
    if geometry.counterweight is None:
        body, _ = occ.cut([(2, outer)], [(2, cavity)])
        return [t for _, t in body], []
    x1, x2 = geometry.counterweight
    slab = occ.addRectangle(-x2, 0.0, 0.0, x2 - x1, p.largest_radius)
    weight, _ = occ.intersect([(2, cavity)], [(2, slab)], removeObject=False)
    body, _ = occ.cut([(2, outer)], [(2, cavity)])
    return [t for _, t in body], [t for _, t in weight]


def _mesh_quarter(geometry: ProjectileGeometry, size: float, order: int) -> ProjectileMesh:
    """Mesh the quarter ``y >= 0, z >= 0`` of the projectile in the current gmsh session."""
    import gmsh

    occ = gmsh.model.occ
    body_faces, weight_faces = _profile_faces(occ, geometry)
    quarter = 0.5 * math.pi

    def revolve(faces: list[int]) -> list[int]:
        out = occ.revolve([(2, f) for f in faces], 0, 0, 0, 1, 0, 0, quarter)
        return [t for d, t in out if d == 3]

    body_vols, weight_vols = revolve(body_faces), revolve(weight_faces)
    if weight_vols:
        # make the body and the counterweight share their interface
        _, mapping = occ.fragment([(3, v) for v in body_vols], [(3, v) for v in weight_vols])
        n_body = len(body_vols)
        body_vols = sorted({t for m in mapping[:n_body] for _, t in m})
        weight_vols = sorted({t for m in mapping[n_body:] for _, t in m} - set(body_vols))
    occ.synchronize()

    # outer surface: boundary surfaces of the union that reach the outer profile's radius over their span
    # (cavity walls stop a wall thickness inside it; the symmetry planes are recognised by lying in y = 0
    # or z = 0)
    profile = geometry.profile
    a = profile.radius
    inner = 0.0 if geometry.interior is None else geometry.interior.wall_thickness
    boundary = gmsh.model.getBoundary([(3, v) for v in body_vols + weight_vols], combined=True, oriented=False)
    outer_surfaces = []
    for _, tag in boundary:
        xmin, ymin, zmin, xmax, ymax, zmax = gmsh.model.getBoundingBox(2, abs(tag))
        # OpenCASCADE pads bounding boxes by its tolerance (~1e-7 m)
        on_plane = (ymax - ymin) < 1e-3 * a or (zmax - zmin) < 1e-3 * a
        reach = float(profile.radius_at(np.linspace(max(-xmax, 0.0), min(-xmin, profile.length), 65)).max())
        if not on_plane and (geometry.interior is None or max(ymax, zmax) > reach - 0.5 * inner):
            outer_surfaces.append(abs(tag))
    gmsh.model.addPhysicalGroup(3, body_vols, BODY, name="body")
    if weight_vols:
        gmsh.model.addPhysicalGroup(3, weight_vols, COUNTERWEIGHT, name="counterweight")
    gmsh.model.addPhysicalGroup(2, outer_surfaces, OUTER, name="outer")

    generate(size, order)
    points, tetrahedra, triangles = elements(order)
    body = tetrahedra(body_vols)
    weight = tetrahedra(weight_vols)
    outer = triangles(outer_surfaces)

    tetra = np.concatenate([body, weight])
    region = np.concatenate([np.full(len(body), BODY), np.full(len(weight), COUNTERWEIGHT)])
    tetra = _orient_tetra(points, tetra)
    outer = _orient_outward(points, outer, geometry)
    return ProjectileMesh(points, tetra, region, outer, order)


def generate(size: float, order: int) -> None:
    """Mesh the current gmsh model with tetrahedra of size ``size`` (m) and geometry order ``order``."""
    import gmsh

    gmsh.option.setNumber("Mesh.MeshSizeMax", size)
    gmsh.option.setNumber("Mesh.MeshSizeMin", 0.1 * size)
    gmsh.option.setNumber("Mesh.MeshSizeExtendFromBoundary", 0)
    gmsh.option.setNumber("Mesh.MeshSizeFromPoints", 0)
    gmsh.option.setNumber("Mesh.Algorithm3D", 10)  # HXT: ~5x faster than Delaunay
    gmsh.option.setNumber("Mesh.ElementOrder", order)
    gmsh.option.setNumber("Mesh.SecondOrderLinear", 0)  # edge nodes on the true geometry
    gmsh.model.mesh.generate(3)


def elements(order: int) -> tuple[np.ndarray, ElementReader, ElementReader]:
    """The nodes of the current gmsh mesh and two readers of its elements in our node order.

    Returns ``(points, tetrahedra, triangles)``: ``tetrahedra(volume_tags)`` and
    ``triangles(surface_tags)`` give the elements of those entities, one row each, as
    indices into ``points``.
    """
    import gmsh

    node_tags, coords, _ = gmsh.model.mesh.getNodes()
    index = np.zeros(int(node_tags.max()) + 1, dtype=np.int64)
    index[node_tags.astype(np.int64)] = np.arange(len(node_tags))
    points = coords.reshape(-1, 3)

    def reader(name: str, edges: tuple[tuple[int, int], ...]) -> ElementReader:
        etype = gmsh.model.mesh.getElementType(name, order)
        cols = _edge_reorder(etype, edges if order == 2 else ())

        def read(tags: list[int]) -> np.ndarray:
            blocks = []
            for tag in tags:
                _, nodes = gmsh.model.mesh.getElementsByType(etype, tag)
                blocks.append(index[nodes.astype(np.int64)].reshape(-1, len(cols))[:, cols])
            return np.concatenate(blocks) if blocks else np.zeros((0, len(cols)), dtype=np.int64)

        return read

    return points, reader("Tetrahedron", TET_EDGES), reader("Triangle", TRI_EDGES)


def _permute(cells: np.ndarray, corner_perm: tuple[int, ...], edges: tuple[tuple[int, int], ...]) -> np.ndarray:
    """Permute the corners of cells and move their edge nodes along."""
    n_corners = len(corner_perm)
    cols = list(corner_perm)
    if cells.shape[1] > n_corners:
        lookup = {frozenset(e): n_corners + k for k, e in enumerate(edges)}
        cols += [lookup[frozenset((corner_perm[i], corner_perm[j]))] for i, j in edges]
    return cells[:, cols]


def _orient_tetra(points: np.ndarray, tetra: np.ndarray) -> np.ndarray:
    """Make every tetrahedron positively oriented."""
    p = points[tetra[:, :4]]
    volume6 = np.einsum("ij,ij->i", np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), p[:, 3] - p[:, 0])
    flipped = volume6 < 0
    tetra = tetra.copy()
    tetra[flipped] = _permute(tetra[flipped], (0, 2, 1, 3), TET_EDGES)
    return tetra


def _orient_outward(points: np.ndarray, tris: np.ndarray, geometry: ProjectileGeometry) -> np.ndarray:
    """Orient outer triangles so that their corner normal points out of the body."""
    p = points[tris[:, :3]]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    centroid = p.mean(axis=1)
    # outward: radial on the lateral surface, backward on the tail disc, forward on a flat front face
    outward = np.column_stack([np.zeros(len(tris)), centroid[:, 1], centroid[:, 2]])
    scale = geometry.profile.length
    outward[np.abs(centroid[:, 0] + scale) < 1e-9 * scale] = (-1.0, 0.0, 0.0)
    if geometry.profile.tip_radius > 0:
        outward[np.abs(centroid[:, 0]) < 1e-9 * scale] = (1.0, 0.0, 0.0)
    flipped = np.einsum("ij,ij->i", normal, outward) < 0
    tris = tris.copy()
    tris[flipped] = _permute(tris[flipped], (0, 2, 1), TRI_EDGES)
    return tris


def outer_triangles(mesh: ProjectileMesh) -> np.ndarray:
    """The outer surface as flat triangles, shape (t, 3, 3) (m): each curved (6-node) triangle split into four
    through its edge nodes, which lie on the surface, so that the flat ones keep a quarter of its sag."""
    outer = mesh.outer
    if mesh.order == 1:
        return mesh.points[outer]
    c0, c1, c2, e01, e12, e02 = (outer[:, k] for k in range(6))  # corners, then edges in TRI_EDGES' order
    split = np.stack([[c0, e01, e02], [e01, c1, e12], [e02, e12, c2], [e01, e12, e02]], axis=1)  # (3, 4, n)
    return mesh.points[split.transpose(2, 1, 0).reshape(-1, 3)]


#: the bit a mirror image in the plane ``x[axis] = 0`` sets in an outer triangle's CAD surface tag
#: (``ProjectileMesh.outer_entity``): the triangle lies on that surface's image (:class:`mesh.cad.CadSurface`)
MIRRORED_ENTITY = {1: 1 << 24, 2: 1 << 25}


def mirror_mesh(mesh: ProjectileMesh, axis: int) -> ProjectileMesh:
    """Union of a mesh with its mirror image in the plane ``x[axis] = 0`` (``axis`` 1 or 2).

    Nodes within 1e-10 of the size of the plane are put on it, so that the image matches bitwise; the
    image's outer triangles keep their CAD surfaces with the mirror's bit (:data:`MIRRORED_ENTITY`).
    """
    points = mesh.points.copy()
    scale = np.abs(points).max()
    on_plane = np.abs(points[:, axis]) <= 1e-10 * scale
    points[on_plane, axis] = 0.0  # exact zeros so that the mirror image matches bitwise
    off = np.flatnonzero(~on_plane)
    image = np.arange(len(points))
    image[off] = len(points) + np.arange(len(off))
    mirrored = points[off].copy()
    mirrored[:, axis] *= -1.0
    tet_perm = (0, 2, 1, 3)  # a reflection flips orientation: swap two corners back
    tri_perm = (0, 2, 1)
    return ProjectileMesh(
        points=np.vstack([points, mirrored]),
        tetra=np.vstack([mesh.tetra, _permute(image[mesh.tetra], tet_perm, TET_EDGES)]),
        tetra_region=np.concatenate([mesh.tetra_region, mesh.tetra_region]),
        outer=np.vstack([mesh.outer, _permute(image[mesh.outer], tri_perm, TRI_EDGES)]),
        order=mesh.order,
        outer_entity=(
            None
            if mesh.outer_entity is None
            else np.concatenate([mesh.outer_entity, mesh.outer_entity ^ MIRRORED_ENTITY[axis]])
        ),
    )


def build_mesh(geometry: ProjectileGeometry, size: float, order: int = 2) -> ProjectileMesh:
    """Mesh a projectile.

    Parameters
    ----------
    geometry : ProjectileGeometry
        Profile, cavity and counterweight.
    size : float
        Target element size (m).
    order : {1, 2}
        Geometry order: 1 for flat (4-node) tetrahedra, 2 for curved 10-node ones.

    Returns
    -------
    ProjectileMesh
        The full mesh, exactly symmetric about the planes ``y = 0`` and ``z = 0``.
    """
    if order not in (1, 2):
        raise ValueError(f"order = {order}: must be 1 or 2")
    if not (0.0 < size < geometry.profile.length and math.isfinite(size)):
        raise ValueError(f"mesh size = {size}: must lie in (0, {geometry.profile.length}) m")
    with gmsh_session("projectile"):
        quarter = _mesh_quarter(geometry, size, order)
    return mirror_mesh(mirror_mesh(quarter, 1), 2)


@contextlib.contextmanager
def gmsh_session(name: str) -> Iterator[None]:
    """A fresh gmsh model named ``name``, one at a time per process, quiet, on one thread (deterministic meshes)."""
    import gmsh

    with _GMSH_LOCK, standard_output_discarded():
        gmsh.initialize(interruptible=False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.option.setNumber("General.NumThreads", 1)
            gmsh.model.add(name)
            yield
        finally:
            gmsh.finalize()


@contextlib.contextmanager
def standard_output_discarded() -> Iterator[None]:
    """Discard what C code prints on file descriptor 1 meanwhile.

    ``General.Terminal = 0`` silences gmsh's own messages, but its HXT mesher prints
    "PLC Error" lines with ``printf`` before it fails; the caller's one-line error
    says what went wrong, and standard output stays the caller's (``--json``).
    """
    sys.stdout.flush()
    try:
        saved = os.dup(1)
    except OSError:  # no standard output to protect
        yield
        return
    try:
        with open(os.devnull, "wb") as devnull:
            os.dup2(devnull.fileno(), 1)
        yield
    finally:
        sys.stdout.flush()  # and Python's: a library's print() goes with it
        with contextlib.suppress(OSError, AttributeError):
            ctypes.CDLL(None).fflush(None)  # C's buffered printf output goes to the discarded descriptor
        os.dup2(saved, 1)
        os.close(saved)
