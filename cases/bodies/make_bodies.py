"""Write the non-axisymmetric projectile bodies of the shipped scenes as STEP files (millimetres).

Run from the repository root: ``.venv/bin/python cases/bodies/make_bodies.py`` (a second or two).
Each body is Forrestal and Luk's validation projectile (95.2 mm diameter, 1.4 m long, CRH 3
tangent-ogive nose, ``cases/forrestal_luk_test2.toml``) built with gmsh's OpenCASCADE kernel along
+x from the tail at x = 0 to the tip, and changed so that it is no longer a body of revolution:

* ``eroded_test2.step``: the nose cut by a plane, as a recovered nose eroded on one side looks.
  The plane crosses the axis ``ERODED_DEPTH`` behind the tip, its normal lies in the x-z plane at
  ``ERODED_ANGLE`` from the axis, and the material on its forward (+x, +z) side is removed: the
  tip and the upper side of the nose.
* ``finned_test2.step``: four thin tail fins (``FIN_*``), in the x-y and x-z planes, fused to the
  body; a body with the symmetries of a square, not of a circle.

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
    nose = math.sqrt(radius ** 2 - (radius - a) ** 2)
    tip, shoulder = occ.addPoint(LENGTH, 0, 0), occ.addPoint(LENGTH - nose, a, 0)
    arc = occ.addCircleArc(tip, occ.addPoint(LENGTH - nose, a - radius, 0), shoulder)
    tail_edge, tail_centre = occ.addPoint(0, a, 0), occ.addPoint(0, 0, 0)
    loop = occ.addCurveLoop([arc, occ.addLine(shoulder, tail_edge), occ.addLine(tail_edge, tail_centre),
                             occ.addLine(tail_centre, tip)])
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
    fins = [occ.addBox(0, -reach, -t, FIN_CHORD, 2 * reach, FIN_THICKNESS),  # in the x-y plane
            occ.addBox(0, -t, -reach, FIN_CHORD, FIN_THICKNESS, 2 * reach)]  # in the x-z plane
    occ.fuse([(3, solid)], [(3, fin) for fin in fins])


BODIES = {"eroded_test2.step": eroded, "finned_test2.step": finned}


def write(folder: Path = HERE) -> list[Path]:
    """Write every body into ``folder`` (STEP, millimetres); the paths written."""
    import gmsh

    written = []
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
