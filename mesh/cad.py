"""CAD solids (STEP, BREP, IGES) through gmsh's OpenCASCADE kernel: their mesh, and quadrature on their exact surfaces.

The solids are imported as the file has them, meshed in the file's units and
the mesh scaled and turned (:func:`~mesh.imported.model_frame`); each outer
triangle keeps the CAD surface it lies on, so that :class:`CadSurface` can
integrate over the exact surface in its own parameters.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from .geometry import TRI_EDGES, ProjectileMesh, _orient_tetra, elements, generate, gmsh_session
from .imported import (
    CAD_SUFFIXES,
    UNITS,
    FileGeometry,
    GeometryError,
    check_size,
    components,
    model_frame,
    orient_by_volume,
    regions,
    rotation_to_x,
)

__all__ = ["cad_mesh", "CadSurface", "load_cad"]


def _declared_unit(path: str) -> str | None:
    """The length unit a STEP file declares (gmsh writes millimetres whatever the numbers mean)."""
    if CAD_SUFFIXES.get(Path(path).suffix.lower()) != "step":
        return None
    with open(path, "rb") as f:
        text = f.read(1 << 20).decode("latin-1").upper()
    for prefix, name in ((".MILLI.", "millimetres"), (".CENTI.", "centimetres"), (".KILO.", "kilometres")):
        if f"SI_UNIT({prefix},.METRE.)" in text.replace(" ", ""):
            return name
    if "INCH" in text:
        return "inches"
    if "SI_UNIT($,.METRE.)" in text.replace(" ", ""):
        return "metres"
    return None


def load_cad(geometry: FileGeometry) -> dict[int, str]:
    """Import the CAD solids into the current gmsh session as the file has them; their names by volume tag.

    The solids are neither scaled nor turned here: OpenCASCADE's general transformation (gmsh's
    ``dilate``) would turn every plane, cylinder and surface of revolution into a B-spline; the
    mesh is scaled and turned instead (:func:`model_frame`), and :class:`CadSurface` maps back.
    """
    import gmsh

    fmt = CAD_SUFFIXES[Path(geometry.path).suffix.lower()]
    occ = gmsh.model.occ
    # the numbers as written: the scene's unit says what they mean (a STEP file's declared unit is often
    # wrong: gmsh itself labels every file millimetres)
    gmsh.option.setString("Geometry.OCCTargetUnit", "")
    try:
        shapes = occ.importShapes(geometry.path, highestDimOnly=True, format=fmt)
    except Exception as exc:
        reason = " ".join(str(exc).split())
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: gmsh cannot read it as {fmt.upper()} ({reason})"
        ) from None
    if shapes and not any(d == 3 for d, _ in shapes):
        _sew_solid(geometry, shapes)
    occ.synchronize()
    volumes = [t for _, t in gmsh.model.getEntities(3)]
    if not volumes:
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: no closed solid (surfaces that do"
            " not close, or that OpenCASCADE cannot sew into one: the body must be a watertight"
            " solid; export it as STEP or BREP)"
        )
    names = {v: _solid_name(gmsh.model.getEntityName(3, v), k) for k, v in enumerate(volumes)}
    check_size(_extent_of([(3, v) for v in volumes]) * UNITS[geometry.unit], geometry, _declared_unit(geometry.path))
    # Split the solids by the two planes through the axis, and make touching solids share their interfaces
    # (one conforming mesh).  gmsh meshes a whole cone badly at its apex, a pole of its parameters on the
    # seam (the triangles there fold over and the volume mesh loses the tip); split into quarters, the apex
    # is a corner of each piece, as in the analytic projectiles' meshes.
    rotation = rotation_to_x(geometry.axis)
    planes = [_plane(occ, rotation[k], 2.0 * _extent_of([(3, v) for v in volumes])) for k in (1, 2)]
    _, mapping = occ.fragment([(3, v) for v in volumes], [(2, p) for p in planes])
    names = {t: names[v] for v, pieces in zip(volumes, mapping) for d, t in pieces if d == 3}
    occ.synchronize()
    solids = [t for _, t in gmsh.model.getEntities(3)]
    bounding = {abs(t) for v in solids for _, t in gmsh.model.getBoundary([(3, v)], oriented=False)}
    occ.remove([(2, t) for _, t in gmsh.model.getEntities(2) if t not in bounding], recursive=True)
    occ.synchronize()
    return {t: names.get(t, f"solid{k + 1}") for k, t in enumerate(solids)}


def _sew_solid(geometry: FileGeometry, shapes: list[tuple[int, int]]) -> None:
    """A solid from loose faces (an IGES file's trimmed surfaces), where they sew into one closed shell."""
    import gmsh

    occ = gmsh.model.occ
    faces = [t for d, t in shapes if d == 2]
    if not faces:
        return
    try:
        loop = occ.addSurfaceLoop(faces, sewing=True)
        volume = occ.addVolume([loop])
        occ.synchronize()
    except Exception:  # OpenCASCADE cannot make a shell of them
        return
    occ.remove(shapes, recursive=True)  # the loose faces: the solid has its own
    occ.synchronize()
    # a shell that does not close: some edge bounds only one face (a seam bounds its face twice; the
    # degenerate edge at a pole, of length zero to the file's precision, bounds one face and closes nothing)
    shell = gmsh.model.getBoundary([(3, volume)], combined=False, oriented=False)
    counts: dict[int, int] = {}
    for _, c in gmsh.model.getBoundary(shell, combined=False, oriented=False):
        counts[abs(c)] = counts.get(abs(c), 0) + 1
    precision = 1e-6 * _extent_of([(3, volume)])
    open_edges = [c for c, n in counts.items() if n < 2 and occ.getMass(1, c) > precision]
    if open_edges or occ.getMass(3, volume) <= 0.0:
        occ.remove([(3, volume)], recursive=True)
        occ.synchronize()


def _plane(occ: Any, normal: np.ndarray, half: float) -> int:
    """A square of side ``2 half`` centred on the origin, normal to ``normal``."""
    square = occ.addRectangle(-half, -half, 0.0, 2.0 * half, 2.0 * half)
    turn = np.cross([0.0, 0.0, 1.0], normal)
    if np.linalg.norm(turn) > 1e-12:
        angle = math.atan2(np.linalg.norm(turn), normal[2])
        occ.rotate([(2, square)], 0.0, 0.0, 0.0, *(turn / np.linalg.norm(turn)), angle)
    return square


def cad_mesh(geometry: FileGeometry, size: float, order: int) -> ProjectileMesh:
    with gmsh_session("file"):
        names = load_cad(geometry)
        volumes = list(names)
        _one_body(geometry, volumes)
        outer = _outer_shell(volumes)
        region_of = regions(geometry, names)
        generate(size / UNITS[geometry.unit], order)
        points, tetrahedra, triangles = elements(order)
        blocks = [tetrahedra([v]) for v in volumes]
        tris = [triangles([s]) for s in outer]
        if order == 2:
            for surface, block in zip(outer, tris):
                _meridian_edge_nodes(points, surface, block)
    tetra = np.concatenate(blocks)
    if len(tetra) == 0:
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: gmsh made no tetrahedra of it (a solid"
            " whose surfaces do not meet edge to edge); export it as STEP or BREP"
        )
    region = np.concatenate([np.full(len(b), region_of[v]) for b, v in zip(blocks, volumes)])
    outer_tris = np.concatenate(tris)
    entity = np.concatenate([np.full(len(t), s) for t, s in zip(tris, outer)])
    used, points_index = np.unique(np.concatenate([tetra.ravel(), outer_tris.ravel()]), return_inverse=True)
    tetra = points_index[: tetra.size].reshape(tetra.shape)
    outer_tris = points_index[tetra.size :].reshape(outer_tris.shape)
    points = model_frame(points[used], geometry)
    tetra = _orient_tetra(points, tetra)
    return ProjectileMesh(
        points, tetra, region, orient_by_volume(points, outer_tris, tetra), order, outer_entity=entity
    )


def _meridian_edge_nodes(points: np.ndarray, surface: int, triangles: np.ndarray) -> None:
    """Move the edge nodes of the edges from a pole of ``surface`` onto their meridians (in place).

    At a pole (the apex of a nose of revolution) the angle parameter is arbitrary, and gmsh puts
    the middle node of an edge from the apex at the parameter halfway between the apex's and
    the other end's: on another meridian, off to the side, which tangles the curved elements
    there.  The edge runs along the other end's meridian: its middle node goes there, halfway
    in the other parameter.  The tetrahedra share the node, so they follow.
    """
    import gmsh

    if len(triangles) == 0:
        return
    uv = _corner_parameters(surface, points[triangles[:, :3]])
    fixes = {}
    for row, corner in zip(*np.nonzero(np.isnan(uv).any(axis=2))):
        d = int(np.flatnonzero(np.isnan(uv[row, corner]))[0])
        for other in (k for k in range(3) if k != corner and not np.isnan(uv[row, k]).any()):
            edge = TRI_EDGES.index(tuple(sorted((corner, other))))
            middle = uv[row, other].copy()
            middle[1 - d] = 0.5 * (uv[row, corner, 1 - d] + uv[row, other, 1 - d])
            fixes[int(triangles[row, 3 + edge])] = middle
    if fixes:
        nodes = list(fixes)
        at = np.asarray(gmsh.model.getValue(2, surface, np.concatenate([fixes[n] for n in nodes]).tolist()))
        points[nodes] = at.reshape(-1, 3)


def _solid_name(label: str, index: int) -> str:
    """A solid's name: the last part of its CAD label (``Shapes/.../counterweight``), else ``solidN``."""
    name = label.rsplit("/", 1)[-1].strip()
    return name or f"solid{index + 1}"


def _extent_of(dim_tags: list[tuple[int, int]]) -> float:
    import gmsh

    boxes = np.array([gmsh.model.occ.getBoundingBox(d, t) for d, t in dim_tags])
    return float(max(np.max(boxes[:, 3:], axis=0) - np.min(boxes[:, :3], axis=0)))


def _one_body(geometry: FileGeometry, volumes: list[int]) -> None:
    """Refuse disjoint bodies: the solids must touch (share a surface) to be one projectile."""
    import gmsh

    faces = {v: {abs(t) for _, t in gmsh.model.getBoundary([(3, v)], oriented=False)} for v in volumes}
    pairs = [(i, j) for i, a in enumerate(volumes) for j, b in enumerate(volumes) if i < j and faces[a] & faces[b]]
    n = len(set(components(len(volumes), pairs).tolist()))
    if n > 1:
        raise GeometryError(
            f"projectile.geometry.file = {geometry.path!r}: {n} disjoint bodies; a projectile is"
            " one body (join the solids in the CAD tool, or keep one)"
        )


def _outer_shell(volumes: list[int]) -> list[int]:
    """The boundary surfaces of the union of ``volumes`` on its outermost shell (closed voids left out)."""
    import gmsh

    boundary = sorted(
        {abs(t) for _, t in gmsh.model.getBoundary([(3, v) for v in volumes], combined=True, oriented=False)}
    )
    curves = {s: {abs(t) for _, t in gmsh.model.getBoundary([(2, s)], oriented=False)} for s in boundary}
    pairs = [(i, j) for i, a in enumerate(boundary) for j, b in enumerate(boundary) if i < j and curves[a] & curves[b]]
    shell = components(len(boundary), pairs)
    # the outer shell encloses every other: it has the largest bounding box
    boxes = np.array([gmsh.model.getBoundingBox(2, s) for s in boundary])
    size = {
        c: np.prod(np.max(boxes[shell == c, 3:], axis=0) - np.min(boxes[shell == c, :3], axis=0))
        for c in set(shell.tolist())
    }
    outer = max(size, key=size.__getitem__)
    return [s for s, c in zip(boundary, shell) if c == outer]


class CadSurface:
    """The exact surface of a CAD projectile, for quadrature on it.

    Parameters
    ----------
    geometry : FileGeometry
        The CAD file, unit and axis the mesh was made from.
    tip : float
        The model frame's x of the tip (:func:`body_frame`): body-frame points are moved back by it.
    """

    def __init__(self, geometry: FileGeometry, tip: float) -> None:
        self.geometry = geometry
        self.tip = tip

    def quadrature(
        self, corners: np.ndarray, entities: np.ndarray, ref_points: np.ndarray, ref_weights: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """A quadrature rule on the CAD surfaces, facet by facet, in their parametric coordinates.

        Each facet's corners are given their parameters ``(u, v)`` on its CAD surface; the
        rule maps onto the straight triangle between them in the parameter plane, and the
        surface ``x(u, v)`` carries it onto the exact surface, with weights
        ``w |det J_uv| |x_u x x_v|`` and the unit normal ``x_u x x_v``.  The facets'
        parameter triangles tile each surface (they share their corners), so the rule
        integrates over the exact surface; a boundary curve that is not straight in the
        parameter plane is followed by chords (an area error of the order of the curvature
        in the parameter plane times the element size squared, per unit length of such a
        boundary).  Planes are left to the caller's facets (their own normals are exact).

        Parameters
        ----------
        corners : ndarray, shape (n, 3, 3)
            The facets' corners (body frame, m).
        entities : ndarray, shape (n,)
            The CAD surface of each facet.
        ref_points : ndarray, shape (2, q)
            The rule's points on the reference triangle (0,0), (1,0), (0,1).
        ref_weights : ndarray, shape (q,)
            Its weights (summing to 1/2).

        Returns
        -------
        points, normals : ndarray, shape (n * q, 3)
            Facet by facet, point by point; body frame; normals as the surface is
            oriented in the file (the caller orients them outward).
        weights : ndarray, shape (n * q,)
            Area weights (m^2).
        planar : ndarray of bool, shape (n,)
            The facets on planes, left as zeros.
        """
        import gmsh

        n, q = len(corners), len(ref_weights)
        scale = UNITS[self.geometry.unit]
        rotation = rotation_to_x(self.geometry.axis)
        shift = np.array([self.tip, 0.0, 0.0])
        points = np.zeros((n, q, 3))
        normals = np.zeros((n, q, 3))
        weights = np.zeros((n, q))
        planar = np.zeros(n, dtype=bool)
        with gmsh_session("surface"):
            load_cad(self.geometry)
            for entity in np.unique(entities).tolist():
                rows = np.flatnonzero(entities == entity)
                if gmsh.model.getType(2, entity) == "Plane":
                    planar[rows] = True
                    continue
                in_file = ((corners[rows] + shift) @ rotation) / scale  # body frame -> the file's coordinates
                at, weight = _parameter_rule(_corner_parameters(entity, in_file), ref_points, ref_weights)
                flat = at.reshape(-1).tolist()
                value = np.asarray(gmsh.model.getValue(2, entity, flat)).reshape(len(rows), q, 3)
                derivative = np.asarray(gmsh.model.getDerivative(2, entity, flat)).reshape(len(rows), q, 2, 3)
                cross = np.cross(derivative[:, :, 0], derivative[:, :, 1])
                jacobian = np.linalg.norm(cross, axis=2)
                points[rows] = scale * value @ rotation.T - shift
                normals[rows] = (cross / np.maximum(jacobian, np.finfo(float).tiny)[..., None]) @ rotation.T
                weights[rows] = weight * jacobian * scale**2
        return points.reshape(-1, 3), normals.reshape(-1, 3), weights.reshape(-1), planar


def _parameter_rule(uv: np.ndarray, ref_points: np.ndarray, ref_weights: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each facet's rule points in its parameter triangle, and their weights in the parameter plane.

    ``uv``: (m, 3, 2) corner parameters, NaN in the degenerate parameter of a corner at a pole
    (:func:`_corner_parameters`).  A facet without a pole maps the triangle rule linearly.  A facet
    with a pole covers the region between the meridians of its other two corners: with ``t``
    across it and ``s`` from the pole, ``a = a1 + (a2 - a1) t`` in the degenerate parameter and
    ``b = (1 - s) b0 + s (1 - t) b1 + s t b2`` in the other, so the facets around a pole tile the
    surface there as they do elsewhere.  The integrand is smooth in ``(t, s)`` but rational in the
    triangle's own coordinates, so those facets take a Gauss-Legendre product rule on the square
    with as many points as the triangle rule has (the few left over carry zero weight).
    """
    q = len(ref_weights)
    xi, eta = ref_points
    at = np.einsum("qk,mkd->mqd", np.column_stack([1.0 - xi - eta, xi, eta]), np.nan_to_num(uv))
    e1, e2 = uv[:, 1] - uv[:, 0], uv[:, 2] - uv[:, 0]
    weight = np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])[:, None] * ref_weights[None, :]
    t, s, square_weights = _square_rule(q)
    for row, corner in zip(*np.nonzero(np.isnan(uv).any(axis=2))):
        d = int(np.flatnonzero(np.isnan(uv[row, corner]))[0])  # the degenerate parameter
        e = 1 - d
        p0, p1, p2 = uv[row, [corner, (corner + 1) % 3, (corner + 2) % 3]]
        across = (1.0 - t) * (p1[e] - p0[e]) + t * (p2[e] - p0[e])
        at[row, :, d] = p1[d] + (p2[d] - p1[d]) * t
        at[row, :, e] = p0[e] + s * across
        weight[row] = square_weights * np.abs((p2[d] - p1[d]) * across)
    return at, weight


def _square_rule(q: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A Gauss-Legendre product rule on the unit square with ``q`` points, padded with zero weights."""
    across = max(1, math.isqrt(q))
    along = q // across
    a, wa = np.polynomial.legendre.leggauss(across)
    b, wb = np.polynomial.legendre.leggauss(along)
    t = np.zeros(q)
    s = np.full(q, 0.5)
    w = np.zeros(q)
    t[: across * along] = np.repeat(0.5 * (a + 1.0), along)
    s[: across * along] = np.tile(0.5 * (b + 1.0), across)
    w[: across * along] = 0.25 * np.outer(wa, wb).ravel()
    return t, s, w


def _corner_parameters(entity: int, corners: np.ndarray) -> np.ndarray:
    """The parameters ``(u, v)`` of each facet's corners on a CAD surface, shape (m, 3, 2).

    A periodic parameter (a surface of revolution's angle) is unwrapped facet by facet so that
    no facet spans the seam the long way round; a corner at a pole (where ``x_u = 0``, the apex
    of a nose) has NaN for the parameter that is arbitrary there (:func:`_parameter_rule`).
    """
    import gmsh

    m = len(corners)
    flat = corners.reshape(-1, 3)
    uv = np.asarray(gmsh.model.getParametrization(2, entity, flat.ravel().tolist())).reshape(m, 3, 2)
    # poles: the derivative along one parameter vanishes there, and that parameter is arbitrary (NaN)
    derivative = np.asarray(gmsh.model.getDerivative(2, entity, uv.reshape(-1).tolist())).reshape(m, 3, 2, 3)
    speed = np.linalg.norm(derivative, axis=3)  # (m, 3, 2)
    poles = [speed[:, :, d] < 1e-9 * np.maximum(speed[:, :, 1 - d], np.finfo(float).tiny) for d in range(2)]
    for d in range(2):
        uv[:, :, d][poles[d]] = np.nan
    low, high = (np.asarray(b) for b in gmsh.model.getParametrizationBounds(2, entity))
    scale = float(np.ptp(flat, axis=0).max()) or 1.0
    # a patch of a periodic surface (a quarter of a surface of revolution across its seam): a corner on
    # the seam may come back a period (an angle: 2 pi) away from the patch
    for d in range(2):
        margin = 1e-9 * max(high[d] - low[d], 1.0)
        for shift in (2.0 * math.pi, -2.0 * math.pi):
            outside = (uv[:, :, d] < low[d] - margin) | (uv[:, :, d] > high[d] + margin)
            moved = uv[:, :, d] + shift
            back = outside & (moved >= low[d] - margin) & (moved <= high[d] + margin)
            if back.any():
                trial = uv[back].copy()
                trial[:, d] += shift
                same = np.asarray(gmsh.model.getValue(2, entity, trial.ravel().tolist())).reshape(-1, 3)
                ok = np.linalg.norm(same - flat.reshape(m, 3, 3)[back], axis=1) < 1e-9 * scale
                rows, cols = np.nonzero(back)
                uv[rows[ok], cols[ok], d] += shift
    for d in range(2):
        period = high[d] - low[d]
        probe = np.array([0.5 * (low + high)] * 2)
        probe[0, d], probe[1, d] = low[d], high[d]
        ends = np.asarray(gmsh.model.getValue(2, entity, probe.ravel().tolist())).reshape(2, 3)
        if np.linalg.norm(ends[0] - ends[1]) < 1e-9 * scale:  # closed in this direction: unwrap
            values = uv[:, :, d]
            with np.errstate(invalid="ignore"):
                wide = np.nanmax(values, axis=1) - np.nanmin(values, axis=1) > 0.5 * period
                values[wide] = np.where(values[wide] < low[d] + 0.5 * period, values[wide] + period, values[wide])
    return uv
