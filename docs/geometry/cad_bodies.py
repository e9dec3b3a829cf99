"""Projectile bodies written as CAD and mesh files by gmsh's own primitives, independently of ``mesh/``.

docs/geometry/files.py and docs/geometry/bodies.py, like the tests of ``mesh.imported``, read them back through
``projectile.geometry`` and compare with the analytic projectiles and with gmsh's (OpenCASCADE's) own mass
properties.  Each writer makes the body along +x from the tail at x = 0 to the tip at x = length, in the
file's unit (``scale`` metres per unit).
"""

from __future__ import annotations

import contextlib
import math
import os
from pathlib import Path

import numpy as np

VALIDATION = {"diameter": 0.0952, "length": 1.4, "crh": 3.0}  # Forrestal and Luk's body (test 2 scene)


def _write(gmsh, path: Path) -> None:
    """``gmsh.write``, with OpenCASCADE's STEP writer's report (printed on the process's own stdout) dropped."""
    import sys

    sys.stdout.flush()
    saved = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            gmsh.write(str(path))
    finally:
        os.dup2(saved, 1)
        os.close(saved)


@contextlib.contextmanager
def _gmsh():
    import gmsh

    gmsh.initialize(interruptible=False)
    gmsh.option.setNumber("General.Terminal", 0)
    try:
        gmsh.model.add("body")
        yield gmsh
    finally:
        gmsh.finalize()


def _revolved(occ, diameter: float, length: float, crh: float | None, half_angle: float | None, scale: float) -> int:
    """An ogive (``crh``) or cone (``half_angle``, deg) nosed cylinder, revolved from its half-profile."""
    a, length = 0.5 * diameter / scale, length / scale
    if crh is not None:
        radius = crh * diameter / scale
        nose = math.sqrt(radius**2 - (radius - a) ** 2)
        tip, shoulder = occ.addPoint(length, 0, 0), occ.addPoint(length - nose, a, 0)
        centre = occ.addPoint(length - nose, a - radius, 0)
        curve = occ.addCircleArc(tip, centre, shoulder)
    else:
        nose = a / math.tan(math.radians(half_angle))
        tip, shoulder = occ.addPoint(length, 0, 0), occ.addPoint(length - nose, a, 0)
        curve = occ.addLine(tip, shoulder)
    tail_edge, tail_centre = occ.addPoint(0, a, 0), occ.addPoint(0, 0, 0)
    loop = occ.addCurveLoop(
        [curve, occ.addLine(shoulder, tail_edge), occ.addLine(tail_edge, tail_centre), occ.addLine(tail_centre, tip)]
    )
    face = occ.addPlaneSurface([loop])
    solid = [t for d, t in occ.revolve([(2, face)], 0, 0, 0, 1, 0, 0, 2 * math.pi) if d == 3][0]
    occ.remove([(2, face)], recursive=True)  # the profile face is no part of the body (IGES would keep it)
    return solid


def write_body(
    path: str | os.PathLike,
    diameter: float = VALIDATION["diameter"],
    length: float = VALIDATION["length"],
    crh: float | None = VALIDATION["crh"],
    half_angle: float | None = None,
    scale: float = 1.0,
    counterweight: tuple[float, float, float] | None = None,
    axis: str = "x",
    offset: tuple[float, float, float] = (0.0, 0.0, 0.0),
) -> Path:
    """Write a nosed cylinder as STEP, BREP or IGES (by the suffix); ``counterweight = (start, end, radius)``
    (m from the tail) adds a second solid inside; ``axis = "z"`` turns the body to run along +z, and then
    ``offset`` (m) moves it."""
    path = Path(path)
    with _gmsh() as gmsh:
        occ = gmsh.model.occ
        body = _revolved(occ, diameter, length, crh if half_angle is None else None, half_angle, scale)
        if counterweight is not None:
            start, end, radius = (v / scale for v in counterweight)
            weight = occ.addCylinder(start, 0, 0, end - start, 0, 0, radius)
            occ.fragment([(3, body)], [(3, weight)])
        _place(occ, axis, offset, scale)
        occ.synchronize()
        _write(gmsh, path)
    return path


def _place(occ, axis: str, offset: tuple[float, float, float], scale: float) -> None:
    """Turn the model's solids from +x onto ``axis`` ("x" or "z"), then move them by ``offset`` (m)."""
    if axis == "z":
        occ.rotate(occ.getEntities(3), 0, 0, 0, 0, 1, 0, -0.5 * math.pi)  # +x onto +z
    if any(offset):
        occ.translate(occ.getEntities(3), *(v / scale for v in offset))


def write_fused_cone(path: str | os.PathLike, half_angle: float = 12.92, scale: float = 1e-3) -> Path:
    """The validation body with a cone nose, as a CAD user draws it: a cylinder fused with a cone (not revolved
    from a profile), written in the unit ``scale`` (default millimetres)."""
    path = Path(path)
    a, length = 0.5 * VALIDATION["diameter"] / scale, VALIDATION["length"] / scale
    nose = a / math.tan(math.radians(half_angle))
    with _gmsh() as gmsh:
        occ = gmsh.model.occ
        cylinder = occ.addCylinder(0, 0, 0, length - nose, 0, 0, a)
        cone = occ.addCone(length - nose, 0, 0, nose, 0, 0, a, 0.0)
        occ.fuse([(3, cylinder)], [(3, cone)])
        occ.synchronize()
        _write(gmsh, path)
    return path


def write_changed_body(
    path: str | os.PathLike,
    diameter: float = 0.105,
    length: float = 0.6,
    crh: float = 2.5,
    recess: tuple[float, float] | None = None,
    fins: tuple[float, ...] = (),
    cut: tuple[float, float, float] | None = None,
    groove: tuple[float, float, float] | None = None,
) -> Path:
    """A tangent-ogive body (m) changed, written as STEP in millimetres: a flat base ``recess = (depth,
    radius)``; tail ``fins`` at the given angles (degrees from +y towards +z; 150 mm long, 30 mm out, 4 mm
    thick); the nose ``cut`` by the plane 40 mm behind the tip whose normal is the given direction (its
    material on the normal's side removed); a ring ``groove = (start, width, depth)`` around the shank, its
    start measured from the tail."""
    path = Path(path)
    scale = 1e-3
    with _gmsh() as gmsh:
        occ = gmsh.model.occ
        solid = _revolved(occ, diameter, length, crh, None, scale)
        a, big = 0.5 * diameter / scale, 4 * diameter / scale
        if recess is not None:
            depth, radius = (v / scale for v in recess)
            pocket = occ.addCylinder(-1.0, 0, 0, depth + 1.0, 0, 0, radius)
            solid = occ.cut([(3, solid)], [(3, pocket)])[0][0][1]
        if groove is not None:
            start, wide, deep = (v / scale for v in groove)
            ring = occ.addCylinder(start, 0, 0, wide, 0, 0, a + 1.0)
            core = occ.addCylinder(start, 0, 0, wide, 0, 0, a - deep)
            cutter = occ.cut([(3, ring)], [(3, core)])[0]
            solid = occ.cut([(3, solid)], cutter)[0][0][1]
        for angle in fins:
            fin = occ.addBox(0, -2.0, a - 1.0, 150.0, 4.0, 31.0)  # standing out along +z, then turned
            occ.rotate([(3, fin)], 0, 0, 0, 1, 0, 0, math.radians(angle - 90.0))
            solid = occ.fuse([(3, solid)], [(3, fin)])[0][0][1]
        if cut is not None:
            cutter = occ.addBox(0, -big, -big, big, 2 * big, 2 * big)  # the half-space x > 0, turned onto the normal
            normal = np.asarray(cut, dtype=float) / np.linalg.norm(cut)
            turn = np.cross([1.0, 0.0, 0.0], normal)
            if np.linalg.norm(turn) > 1e-12:
                angle = math.atan2(np.linalg.norm(turn), normal[0])
                occ.rotate([(3, cutter)], 0, 0, 0, *(turn / np.linalg.norm(turn)), angle)
            occ.translate([(3, cutter)], length / scale - 40.0, 0, 0)
            occ.cut([(3, solid)], [(3, cutter)])
        occ.synchronize()
        _write(gmsh, path)
    return path


def write_volume_mesh(path: str | os.PathLike, size: float, order: int = 2, counterweight=None, **body) -> Path:
    """Mesh a body with gmsh and write it as ``.msh`` (physical groups "body", "counterweight") or, through
    meshio, any other format (cell data ``material``: 1 body, 2 counterweight)."""
    import meshio

    path = Path(path)
    msh = path if path.suffix == ".msh" else path.with_name(path.stem + ".gmsh.msh")
    with _gmsh() as gmsh:
        occ = gmsh.model.occ
        crh, half_angle = body.get("crh", VALIDATION["crh"]), body.get("half_angle")
        solid = _revolved(
            occ,
            body.get("diameter", VALIDATION["diameter"]),
            body.get("length", VALIDATION["length"]),
            crh if half_angle is None else None,
            half_angle,
            1.0,
        )
        volumes = {"body": [solid]}
        if counterweight is not None:
            start, end, radius = counterweight
            weight = occ.addCylinder(start, 0, 0, end - start, 0, 0, radius)
            _, mapping = occ.fragment([(3, solid)], [(3, weight)])
            volumes = {
                "body": [t for _, t in mapping[0] if (3, t) not in mapping[1]],
                "counterweight": [t for _, t in mapping[1]],
            }
        occ.synchronize()
        for tag, (name, tags) in enumerate(volumes.items(), 1):
            gmsh.model.addPhysicalGroup(3, tags, tag, name=name)
        gmsh.option.setNumber("Mesh.MeshSizeMax", size)
        gmsh.option.setNumber("Mesh.MeshSizeMin", 0.1 * size)
        gmsh.option.setNumber("Mesh.ElementOrder", order)
        # curved elements at the tip fold over unless optimised: 1 moves the poor ones only (as penetrate's own CAD
        # meshing does), as valid as 2 (elastic, then optimised) and far cheaper at 5 mm
        gmsh.option.setNumber("Mesh.HighOrderOptimize", 1)
        gmsh.model.mesh.generate(3)
        gmsh.option.setNumber("Mesh.MshFileVersion", 4.1)
        gmsh.write(str(msh))
    if path.suffix != ".msh":
        m = meshio.read(msh)
        tets = [(b.type, b.data) for b in m.cells if b.type.startswith("tetra")]
        material = [
            np.asarray(m.cell_data["gmsh:physical"][k]) for k, b in enumerate(m.cells) if b.type.startswith("tetra")
        ]
        meshio.write(path, meshio.Mesh(m.points, tets, cell_data={"material": material}))
        msh.unlink()
    return path


def occ_mass_properties(path: str | os.PathLike, density: float = 1.0, scale: float = 1.0):
    """OpenCASCADE's own mass, centre and inertia tensor about the centre of the solids in a CAD file
    (SI units for a file in units of ``scale`` metres), from gmsh's ``occ.getMass`` and friends."""
    with _gmsh() as gmsh:
        gmsh.option.setString("Geometry.OCCTargetUnit", "")
        shapes = gmsh.model.occ.importShapes(str(path))
        gmsh.model.occ.synchronize()
        volumes = [t for d, t in shapes if d == 3]
        mass = sum(gmsh.model.occ.getMass(3, v) for v in volumes)
        centre = (
            sum(np.array(gmsh.model.occ.getCenterOfMass(3, v)) * gmsh.model.occ.getMass(3, v) for v in volumes) / mass
        )
        inertia = np.zeros((3, 3))
        for v in volumes:  # each solid's tensor is about its own centre (OpenCASCADE): move it to the common one
            m, c = gmsh.model.occ.getMass(3, v), np.array(gmsh.model.occ.getCenterOfMass(3, v))
            d = c - centre
            inertia += np.array(gmsh.model.occ.getMatrixOfInertia(3, v)).reshape(3, 3) + m * (
                d @ d * np.eye(3) - np.outer(d, d)
            )
    return mass * density * scale**3, centre * scale, inertia * density * scale**5
