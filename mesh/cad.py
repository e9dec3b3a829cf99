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

from .geometry import (
    MIRRORED_ENTITY,
    TRI_EDGES,
    ProjectileMesh,
    _orient_tetra,
    elements,
    generate,
    gmsh_session,
    mirror_mesh,
)
from .imported import (
    CAD_SUFFIXES,
    UNITS,
    FileGeometry,
    GeometryError,
    check_size,
    components,
    model_frame,
    orient_by_volume,
    place,
    regions,
    rotation_to_x,
)
from .parameters import node_parameters, parameter_rule, straighten_inner_edges
from .symmetry import mirror_planes

__all__ = ["cad_mesh", "CadSurface", "load_cad", "place_cad", "HIGH_ORDER_OPTIMIZE"]

#: gmsh's ``Mesh.HighOrderOptimize`` for a CAD body's curved elements: 1, optimise the poor ones
HIGH_ORDER_OPTIMIZE = 1


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


def place_cad(geometry: FileGeometry) -> FileGeometry:
    """``geometry`` with its axis and origin found from the CAD body (:func:`~mesh.imported.place`): its
    centroid and inertia from OpenCASCADE, its ends along a direction from the bounding box of a turned copy."""
    import gmsh

    occ = gmsh.model.occ
    with gmsh_session("place"):
        volumes = list(_import(geometry))
        masses = np.array([occ.getMass(3, v) for v in volumes])
        centres = np.array([occ.getCenterOfMass(3, v) for v in volumes])
        centroid = masses @ centres / masses.sum()
        inertia = np.zeros((3, 3))
        for v, m, c in zip(volumes, masses, centres):  # each about its own centroid, moved to the body's
            d = c - centroid
            inertia += np.reshape(occ.getMatrixOfInertia(3, v), (3, 3)) + m * ((d @ d) * np.eye(3) - np.outer(d, d))

        def span(direction: np.ndarray) -> tuple[float, float]:
            from scipy.spatial.transform import Rotation

            copy = occ.copy([(3, v) for v in volumes])
            turn = Rotation.from_matrix(rotation_to_x(tuple(direction))).as_rotvec()  # the body frame's turn
            angle = float(np.linalg.norm(turn))
            if angle > 1e-12:
                occ.rotate(copy, 0.0, 0.0, 0.0, *(turn / angle).tolist(), angle)
            boxes = np.array([occ.getBoundingBox(d, t) for d, t in copy])
            occ.remove(copy, recursive=True)
            return float(boxes[:, 0].min()), float(boxes[:, 3].max())

        return place(geometry, centroid, inertia, span)


def load_cad(geometry: FileGeometry) -> dict[int, str]:
    """Import the CAD solids into the current gmsh session as the file has them, and split them by the planes
    through the axis; the pieces' names by volume tag.

    The solids are neither moved, scaled nor turned here: OpenCASCADE's general transformation (gmsh's
    ``dilate``) would turn every plane, cylinder and surface of revolution into a B-spline; the
    mesh is scaled and turned instead (:func:`model_frame`), and :class:`CadSurface` maps back.
    """
    return _split(geometry, _import(geometry))


def _import(geometry: FileGeometry) -> dict[int, str]:
    """Import the CAD solids as the file has them (sewn from loose faces where they close); names by volume tag."""
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
    return names


def _split(geometry: FileGeometry, names: dict[int, str]) -> dict[int, str]:
    """Split the imported solids by the planes through the axis; the pieces' names by volume tag."""
    import gmsh

    occ = gmsh.model.occ
    volumes = list(names)
    # Split the solids by the two planes through the axis, and make touching solids share their interfaces
    # (one conforming mesh).  gmsh meshes a whole cone badly at its apex, a pole of its parameters on the
    # seam (the triangles there fold over and the volume mesh loses the tip); split into quarters, the apex
    # is a corner of each piece, as in the analytic projectiles' meshes.
    rotation = geometry.rotation
    half = 2.0 * _extent_of([(3, v) for v in volumes])
    planes = [_plane(occ, rotation[k], half, geometry.centre) for k in (1, 2)]
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


def _plane(occ: Any, normal: np.ndarray, half: float, centre: np.ndarray) -> int:
    """A square of side ``2 half`` centred on ``centre``, normal to ``normal``."""
    square = occ.addRectangle(-half, -half, 0.0, 2.0 * half, 2.0 * half)
    turn = np.cross([0.0, 0.0, 1.0], normal)
    if np.linalg.norm(turn) > 1e-12:
        angle = math.atan2(np.linalg.norm(turn), normal[2])
        occ.rotate([(2, square)], 0.0, 0.0, 0.0, *(turn / np.linalg.norm(turn)), angle)
    if centre.any():
        occ.translate([(2, square)], *centre.tolist())
    return square


def cad_mesh(geometry: FileGeometry, size: float, order: int) -> ProjectileMesh:
    """The mesh of a CAD body in its model frame (``geometry`` placed first if it is not): meshed whole, or on
    one side of its mirror planes (:mod:`mesh.symmetry`) and mirrored."""
    import gmsh

    geometry = geometry if geometry.placed else place_cad(geometry)
    with gmsh_session("file"):
        names = _import(geometry)
        planes = mirror_planes(geometry, list(names))
        names = _split(geometry, names)
        _one_body(geometry, list(names))
        names = _fundamental_part(geometry, names, planes)
        volumes = list(names)
        cuts = {s for _, s in gmsh.model.getEntities(2) if _on_mirror_plane(geometry, s, planes)}
        outer = _outer_shell(volumes, cuts)
        region_of = regions(geometry, names)
        # curved elements at a sharp tip or a cone fold over at usual sizes (an edge node pulled through the
        # element); gmsh's optimisation moves the high-order nodes of the elements whose Jacobian is poor
        # (below Mesh.HighOrderThresholdMin) and leaves the others as they are
        gmsh.option.setNumber("Mesh.HighOrderOptimize", HIGH_ORDER_OPTIMIZE)
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
    mesh = ProjectileMesh(
        points, tetra, region, orient_by_volume(points, outer_tris, tetra), order, outer_entity=entity
    )
    for axis in planes:
        mesh = mirror_mesh(mesh, axis)
    return mesh


def _fundamental_part(geometry: FileGeometry, names: dict[int, str], planes: tuple[int, ...]) -> dict[int, str]:
    """The pieces on the positive side of each mirror plane (the others are their images); the rest removed."""
    import gmsh

    if not planes:
        return names
    rotation, centre = geometry.rotation, geometry.centre
    occ = gmsh.model.occ
    kept = {
        v: name
        for v, name in names.items()
        if all(float(rotation[axis] @ (np.asarray(occ.getCenterOfMass(3, v)) - centre)) > 0.0 for axis in planes)
    }
    occ.remove([(3, v) for v in names if v not in kept], recursive=True)
    occ.synchronize()
    return kept


def _on_mirror_plane(geometry: FileGeometry, surface: int, planes: tuple[int, ...]) -> bool:
    """Whether a surface lies in one of the mirror planes: a cut through the body, inside the mirrored mesh."""
    import gmsh

    if not planes or gmsh.model.getType(2, surface) != "Plane":
        return False
    rotation = geometry.rotation
    # three points of the plane: its parametrisation's corners (a plane's parameters span the plane itself)
    low, high = (np.asarray(b) for b in gmsh.model.getParametrizationBounds(2, surface))
    samples = np.array([low, [high[0], low[1]], [low[0], high[1]]])
    points = np.asarray(gmsh.model.getValue(2, surface, samples.ravel().tolist())).reshape(3, 3) - geometry.centre
    extent = float(np.ptp(points, axis=0).max())
    return any(bool(np.abs(points @ rotation[axis]).max() <= 1e-9 * extent) for axis in planes)


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
    uv = node_parameters(surface, points[triangles[:, :3]])
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


def _outer_shell(volumes: list[int], cuts: set[int] | frozenset[int] = frozenset()) -> list[int]:
    """The boundary surfaces of the union of ``volumes`` on its outermost shell (closed voids left out), less the
    surfaces ``cuts`` (the mirror planes' faces of a part to be mirrored: a void they cut stays apart)."""
    import gmsh

    boundary = sorted(
        {abs(t) for _, t in gmsh.model.getBoundary([(3, v) for v in volumes], combined=True, oriented=False)} - cuts
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
        The CAD file, unit and axis the mesh was made from (placed here if it is not).
    tip : float
        The model frame's x of the tip (:func:`body_frame`): body-frame points are moved back by it.
    """

    def __init__(self, geometry: FileGeometry, tip: float) -> None:
        self.geometry = geometry if geometry.placed else place_cad(geometry)
        self.tip = tip

    def quadrature(
        self, nodes: np.ndarray, entities: np.ndarray, ref_points: np.ndarray, ref_weights: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """A quadrature rule on the CAD surfaces, facet by facet, in their parametric coordinates.

        Each facet's nodes are given their parameters ``(u, v)`` on its CAD surface; the rule
        maps onto the triangle they span in the parameter plane (straight between three corners;
        quadratic through six nodes, so that an edge on a curved boundary of the surface, where the
        mesh puts its edge node on the boundary, follows it), and the surface ``x(u, v)`` carries
        it onto the exact surface, with weights ``w |det J_uv| |x_u x x_v|`` and the unit normal
        ``x_u x x_v``.  The facets' parameter triangles tile each surface (they share their
        nodes), so the rule integrates over the exact surface; with corners only, a boundary curve
        that is not straight in the parameter plane is followed by chords (an area error of the
        order of its curvature in the parameter plane times the element size squared, per unit
        length of it).  Planes are left to the caller's facets (their own normals are exact).

        Parameters
        ----------
        nodes : ndarray, shape (n, 3, 3) or (n, 6, 3)
            The facets' corners, or corners and edge nodes in the order of
            :data:`~mesh.geometry.TRI_EDGES` (body frame, m).
        entities : ndarray, shape (n,)
            The CAD surface of each facet (with a mirror's bit, :data:`~mesh.geometry.MIRRORED_ENTITY`, for a
            facet on its image).
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

        n, q = len(nodes), len(ref_weights)
        scale = UNITS[self.geometry.unit]
        rotation, centre = self.geometry.rotation, self.geometry.centre
        shift = np.array([self.tip, 0.0, 0.0])
        points = np.zeros((n, q, 3))
        normals = np.zeros((n, q, 3))
        weights = np.zeros((n, q))
        planar = np.zeros(n, dtype=bool)
        with gmsh_session("surface"):
            load_cad(self.geometry)
            for code in np.unique(entities).tolist():
                rows = np.flatnonzero(entities == code)
                # a mirrored triangle lies on the image of its surface: map it back, and the rule's points out
                entity, signs = code, np.ones(3)
                for axis, bit in MIRRORED_ENTITY.items():
                    if code & bit:
                        entity, signs[axis] = entity ^ bit, -1.0
                if gmsh.model.getType(2, entity) == "Plane":
                    planar[rows] = True
                    continue
                # body frame -> the file's coordinates
                in_file = ((nodes[rows] * signs + shift) @ rotation) / scale + centre
                uv = node_parameters(entity, in_file)
                if uv.shape[1] == 6:
                    straighten_inner_edges(uv, nodes[rows, 3:])
                at, weight = parameter_rule(uv, ref_points, ref_weights)
                flat = at.reshape(-1).tolist()
                value = np.asarray(gmsh.model.getValue(2, entity, flat)).reshape(len(rows), q, 3)
                derivative = np.asarray(gmsh.model.getDerivative(2, entity, flat)).reshape(len(rows), q, 2, 3)
                cross = np.cross(derivative[:, :, 0], derivative[:, :, 1])
                jacobian = np.linalg.norm(cross, axis=2)
                points[rows] = (scale * (value - centre) @ rotation.T - shift) * signs
                normals[rows] = (cross / np.maximum(jacobian, np.finfo(float).tiny)[..., None]) @ rotation.T * signs
                weights[rows] = weight * jacobian * scale**2
        return points.reshape(-1, 3), normals.reshape(-1, 3), weights.reshape(-1), planar
