"""Write the non-axisymmetric projectile bodies of the shipped scenes as CAD files.

Run from the repository root: ``.venv/bin/python cases/bodies/make_bodies.py`` (a second or two).
Each body is built with gmsh's OpenCASCADE kernel along +x from the tail at x = 0 to the tip, and
changed so that it is no longer a body of revolution.  Two are Forrestal and Luk's validation
projectile (95.2 mm diameter, 1.4 m long, CRH 3 tangent-ogive nose, ``cases/forrestal_luk_test2.toml``;
STEP, millimetres):

* ``eroded_test2.step``: the nose cut by a plane, as a recovered nose eroded on one side looks.
  The plane crosses the axis ``ERODED_DEPTH`` behind the tip, its normal lies in the x-z plane at
  ``ERODED_ANGLE`` from the axis, and the material on its forward (+x, +z) side is removed: the
  tip and the upper side of the nose.
* ``finned_test2.step``: four thin tail fins (``FIN_*``), in the x-y and x-z planes, fused to the
  body; a body with the symmetries of a square, not of a circle.

The third is the 155 mm family's #3 (``cases/paper_p3.toml``) with a solid nose, its steel body and
tungsten counterweight as two solids, the nose cut in the same way (``eroded_p3.brep``, metres;
:func:`eroded_p3`, whose angle and depth the eroded-nose study of docs/evidence-geometry.md varies).

This module imports nothing of the project: it only makes files, which the scenes read through
``projectile.geometry`` like any CAD file (docs/geometry.md).
"""

from __future__ import annotations

import math
import sys
from pathlib import Path

HERE = Path(__file__).resolve().parent
DIAMETER, LENGTH, CRH = 95.2, 1400.0, 3.0  # mm
ERODED_DEPTH, ERODED_ANGLE = 30.0, 60.0  # mm behind the tip, degrees from the axis
FIN_CHORD, FIN_SPAN, FIN_THICKNESS = 150.0, 40.0, 4.0  # mm: axial length, height above the body, thickness


def body(occ) -> int:
    """The validation projectile as one solid, revolved from its half-profile (mm)."""
    a = DIAMETER / 2
    radius = CRH * DIAMETER
    nose = math.sqrt(radius**2 - (radius - a) ** 2)
    tip, shoulder = occ.addPoint(LENGTH, 0, 0), occ.addPoint(LENGTH - nose, a, 0)
    arc = occ.addCircleArc(tip, occ.addPoint(LENGTH - nose, a - radius, 0), shoulder)
    tail_edge, tail_centre = occ.addPoint(0, a, 0), occ.addPoint(0, 0, 0)
    loop = occ.addCurveLoop(
        [arc, occ.addLine(shoulder, tail_edge), occ.addLine(tail_edge, tail_centre), occ.addLine(tail_centre, tip)]
    )
    face = occ.addPlaneSurface([loop])
    solid = [t for d, t in occ.revolve([(2, face)], 0, 0, 0, 1, 0, 0, 2 * math.pi) if d == 3][0]
    occ.remove([(2, face)], recursive=True)
    return solid


def eroded(occ) -> None:
    """The body minus the half-space in front of the oblique plane."""
    solid = body(occ)
    size = 4 * DIAMETER
    # a box on the +x side of its own plane x = 0, turned so that its normal is (cos, 0, sin) of the angle
    cutter = occ.addBox(0, -size, -size, size, 2 * size, 2 * size)
    occ.rotate([(3, cutter)], 0, 0, 0, 0, 1, 0, -math.radians(ERODED_ANGLE))
    occ.translate([(3, cutter)], LENGTH - ERODED_DEPTH, 0, 0)
    occ.cut([(3, solid)], [(3, cutter)])


def finned(occ) -> None:
    """The body with four fins at the tail, fused into one solid."""
    solid = body(occ)
    a = DIAMETER / 2
    reach = a + FIN_SPAN
    t = FIN_THICKNESS / 2
    fins = [
        occ.addBox(0, -reach, -t, FIN_CHORD, 2 * reach, FIN_THICKNESS),  # in the x-y plane
        occ.addBox(0, -t, -reach, FIN_CHORD, FIN_THICKNESS, 2 * reach),
    ]  # in the x-z plane
    occ.fuse([(3, solid)], [(3, fin) for fin in fins])


# The 155 mm family's #3 (docs/paper.md) with its nose eroded on one side, for the study of docs/evidence-geometry.md.
# The stand-in interior (a 10 mm wall all the way to 21 mm behind the tip) would open to any cut of the
# nose; a penetrator's nose is solid, so here the cavity starts SOLID_NOSE behind the tip, and the
# tungsten counterweight is placed again for #3's mass and centre of mass (:func:`p3_counterweight`).
P3_DIAMETER, P3_LENGTH, P3_CRH = 0.155, 0.93, 5.0  # m, m, calibres
P3_MASS, P3_CENTRE = 75.67, 0.5636 * 0.93  # kg, m from the tip
STEEL, TUNGSTEN = 7850.0, 18000.0  # kg/m^3
WALL, TAIL_PLATE, SOLID_NOSE = 0.01, 0.02, 0.15  # m
P3_ERODED_DEPTH, P3_ERODED_ANGLE = 0.04, 60.0  # the shipped body's cut: m behind the tip, degrees from the axis


def _p3_radius(s, inner: bool = False):
    """The outer radius of #3 (or the cavity's, a wall thickness less) at ``s`` m from the tip."""
    import numpy as np

    a, big_r = P3_DIAMETER / 2, P3_CRH * P3_DIAMETER
    nose = math.sqrt(big_r**2 - (big_r - a) ** 2)
    s = np.asarray(s, dtype=float)
    r = np.where(s < nose, a - big_r + np.sqrt(np.maximum(big_r**2 - (s - nose) ** 2, 0.0)), a)
    return np.maximum(r - WALL, 0.0) if inner else r


def p3_counterweight() -> tuple[float, float]:
    """``(start, end)`` (m from the tip) of the counterweight that gives #3 its mass and centre of mass, with
    the solid nose: two equations of 1-D integrals of the profile, solved by Newton's method (scipy)."""
    from scipy import integrate, optimize

    def moments(s0, s1, inner):
        volume = integrate.quad(lambda s: math.pi * _p3_radius(s, inner) ** 2, s0, s1, limit=200)[0]
        first = integrate.quad(lambda s: math.pi * _p3_radius(s, inner) ** 2 * s, s0, s1, limit=200)[0]
        return volume, first

    outer = moments(0.0, P3_LENGTH, False)
    cavity = moments(SOLID_NOSE, P3_LENGTH - TAIL_PLATE, True)
    shell = (STEEL * (outer[0] - cavity[0]), STEEL * (outer[1] - cavity[1]))

    def residual(span):
        weight = moments(span[0], span[1], True)
        mass = shell[0] + TUNGSTEN * weight[0]
        return [mass - P3_MASS, (shell[1] + TUNGSTEN * weight[1]) / mass - P3_CENTRE]

    span, info, found, message = optimize.fsolve(residual, [0.4, 0.6], full_output=True, xtol=1e-12)
    if found != 1 or not SOLID_NOSE < span[0] < span[1] < P3_LENGTH - TAIL_PLATE:
        raise RuntimeError(f"no counterweight gives #3's mass and centre of mass: {message}")
    return float(span[0]), float(span[1])


def _revolved_face(occ, points_xr: list[tuple[float, float]], arc_centre: tuple[float, float] | None) -> int:
    """A plane face in x-y (y the radius) bounded by straight edges through ``points_xr``, the first edge an arc
    about ``arc_centre`` when given; revolved about the x axis into a solid."""
    tags = [occ.addPoint(x, r, 0.0) for x, r in points_xr]
    edges = []
    for k in range(len(tags)):
        first, second = tags[k], tags[(k + 1) % len(tags)]
        if k == 0 and arc_centre is not None:
            edges.append(occ.addCircleArc(first, occ.addPoint(*arc_centre, 0.0), second))
        else:
            edges.append(occ.addLine(first, second))
    face = occ.addPlaneSurface([occ.addCurveLoop(edges)])
    solid = [t for d, t in occ.revolve([(2, face)], 0, 0, 0, 1, 0, 0, 2 * math.pi) if d == 3][0]
    occ.remove([(2, face)], recursive=True)
    return solid


def eroded_p3(occ, angle: float = P3_ERODED_ANGLE, depth: float = P3_ERODED_DEPTH) -> None:
    """#3 along +x from the tail (x = 0) to the tip (metres), its steel body and tungsten counterweight as two
    solids (the counterweight second), the nose cut by a plane ``depth`` behind the tip with its normal in the
    x-z plane at ``angle`` degrees from the axis (0: a flat, symmetric cut); ``depth`` 0: the whole body."""
    a, big_r, length = P3_DIAMETER / 2, P3_CRH * P3_DIAMETER, P3_LENGTH
    # the plane meets the cavity's apex ring (SOLID_NOSE behind the tip) at depth + r_i tan(angle) from the tip
    reach = depth + float(_p3_radius(SOLID_NOSE, True)) * math.tan(math.radians(angle))
    if depth > 0.0 and not (0.0 <= angle < 90.0 and reach < SOLID_NOSE):
        raise ValueError(
            f"a cut {depth} m behind the tip at {angle} deg would open the cavity"
            f" ({SOLID_NOSE} m behind the tip): a shallower or less oblique cut"
        )
    nose = math.sqrt(big_r**2 - (big_r - a) ** 2)
    centre = (length - nose, a - big_r)  # the ogive's centre, x and radius
    outer = _revolved_face(occ, [(length, 0.0), (length - nose, a), (0.0, a), (0.0, 0.0)], centre)
    apex = length - SOLID_NOSE
    cavity = _revolved_face(
        occ,
        [
            (apex, float(_p3_radius(SOLID_NOSE, True))),
            (length - nose, a - WALL),
            (TAIL_PLATE, a - WALL),
            (TAIL_PLATE, 0.0),
            (apex, 0.0),
        ],
        (centre[0], centre[1] - WALL),
    )
    start, end = p3_counterweight()
    slab = occ.addBox(length - end, -a, -a, end - start, 2 * a, 2 * a)
    weight, _ = occ.intersect([(3, cavity)], [(3, slab)], removeObject=False)
    body, _ = occ.cut([(3, outer)], [(3, cavity)])
    if depth > 0.0:
        size = 4 * P3_DIAMETER
        cutter = occ.addBox(0, -size, -size, size, 2 * size, 2 * size)
        occ.rotate([(3, cutter)], 0, 0, 0, 0, 1, 0, -math.radians(angle))
        occ.translate([(3, cutter)], length - depth, 0, 0)
        body, _ = occ.cut(body, [(3, cutter)])
    occ.fragment(body, weight)


def write_eroded_p3(path: Path, angle: float, depth: float) -> Path:
    """One eroded #3 as a BREP file (metres; solid1 the steel body, solid2 the counterweight)."""
    import gmsh

    gmsh.initialize(interruptible=False)
    try:
        gmsh.option.setNumber("General.Terminal", 0)
        gmsh.model.add("eroded_p3")
        eroded_p3(gmsh.model.occ, angle, depth)
        gmsh.model.occ.removeAllDuplicates()
        gmsh.model.occ.synchronize()
        gmsh.write(str(path))
    finally:
        gmsh.finalize()
    return path


BODIES = {"eroded_test2.step": eroded, "finned_test2.step": finned}


def write(folder: Path = HERE) -> list[Path]:
    """Write every body into ``folder`` (STEP, millimetres; the eroded #3 as BREP, metres); the paths written."""
    import gmsh

    written = [write_eroded_p3(folder / "eroded_p3.brep", P3_ERODED_ANGLE, P3_ERODED_DEPTH)]
    for name, build in BODIES.items():
        gmsh.initialize(interruptible=False)
        try:
            gmsh.option.setNumber("General.Terminal", 0)
            gmsh.model.add(name)
            build(gmsh.model.occ)
            gmsh.model.occ.removeAllDuplicates()
            gmsh.model.occ.synchronize()
            gmsh.write(str(folder / name))
        finally:
            gmsh.finalize()
        written.append(folder / name)
    return written


if __name__ == "__main__":
    for path in write(Path(sys.argv[1]) if len(sys.argv) > 1 else HERE):
        print(path)
