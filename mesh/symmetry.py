"""The mirror planes of a CAD body through its axis, found or checked with OpenCASCADE before meshing.

A body read from a file is meshed as the file has it, and gmsh meshes each piece on its own: the
mesh of a body of revolution is then not its own mirror image, and a straight shot turns by the
mesh's asymmetry (0.1-2 degrees).  A body that is its own mirror image in the body frame's plane
``y = 0``, in ``z = 0``, or in both, is meshed on one side of its planes only (the half, or the
quarter ``y > 0, z > 0``), and the mesh mirrored in numpy (:func:`mesh.geometry.mirror_mesh`), as
the analytic projectiles are: the mesh, mass properties and quadrature are then mirror symmetric
bitwise, and a state in a mirror plane stays in it exactly (docs/geometry.md).

The test: the volume of the body less its image, ``V(A \\ M(A))``, relative to the body's
volume, for every solid on its own (a body and its counterweight are each their own image).
OpenCASCADE's boolean difference of a solid and its exact image is empty, to its precision;
the eroded nose of ``cases/eroded_test2.toml`` differs from its image in ``z = 0`` by 3e-3 of its
volume.  A body of revolution is also its own image under a turn about its axis (1 radian, any
angle not a fraction of a full turn would do).
"""

from __future__ import annotations

import math
from typing import TYPE_CHECKING

from .imported import FileGeometry, GeometryError

if TYPE_CHECKING:
    from collections.abc import Callable

__all__ = ["SYMMETRIES", "SYMMETRY_TOLERANCE", "PLANE_NAMES", "mirror_planes"]

#: what ``projectile.geometry.symmetry`` can say, and the mirror planes (axes: 1 for ``y = 0``, 2 for ``z = 0``)
#: of each declared one; "auto" finds them
SYMMETRIES: dict[str, tuple[int, ...]] = {
    "auto": (),
    "none": (),
    "mirror_y": (1,),
    "mirror_z": (2,),
    "mirrors": (1, 2),
    "revolution": (1, 2),
}
#: the largest ``V(A \ M(A)) / V(A)`` of a body called its own image
SYMMETRY_TOLERANCE = 1e-6
PLANE_NAMES = {1: "y = 0", 2: "z = 0"}
_TURN = 1.0  # rad: the test turn of a body of revolution


def _difference(volumes: list[int], transform: Callable[[list[tuple[int, int]]], None]) -> float:
    """``sum V(A \\ T(A)) / sum V(A)`` over the solids ``volumes`` of the current gmsh model; inf when
    OpenCASCADE cannot take the difference."""
    import gmsh

    occ = gmsh.model.occ
    total = sum(occ.getMass(3, v) for v in volumes)
    left = 0.0
    for v in volumes:
        image = occ.copy([(3, v)])
        try:
            transform(image)
            rest, _ = occ.cut([(3, v)], image, removeObject=False, removeTool=False)
        except Exception:  # "Difference failed - BOPAlgo_AlertBuilderFailed": no answer, so not symmetric
            occ.remove(image, recursive=True)
            return math.inf
        left += sum(occ.getMass(d, t) for d, t in rest)
        occ.remove(rest + image, recursive=True)
    return left / total


def mirror_planes(geometry: FileGeometry, volumes: list[int]) -> tuple[int, ...]:
    """The mirror planes to mesh the solids ``volumes`` (in the current gmsh model, in the file's coordinates)
    by: those ``geometry.symmetry`` declares, checked, or with ``"auto"`` those the body has.

    Raises
    ------
    GeometryError
        A declared symmetry the body does not have (or that OpenCASCADE cannot check).
    """
    import gmsh

    declared = geometry.symmetry
    if declared == "none":
        return ()
    rotation = geometry.rotation  # its rows: the body frame's axes in the file's coordinates
    centre = geometry.centre  # a point of the axis, where the planes meet
    occ = gmsh.model.occ
    differences = {}
    for axis in (1, 2) if declared == "auto" else SYMMETRIES[declared]:
        a, b, c = rotation[axis].tolist()
        d = -float(rotation[axis] @ centre)  # the plane a x + b y + c z + d = 0 through the axis

        def mirror(image: list[tuple[int, int]], a: float = a, b: float = b, c: float = c, d: float = d) -> None:
            occ.mirror(image, a, b, c, d)

        differences[axis] = _difference(volumes, mirror)
    if declared == "auto":
        return tuple(axis for axis, d in differences.items() if d <= SYMMETRY_TOLERANCE)
    field = f'projectile.geometry.symmetry = "{declared}"'
    for axis, d in differences.items():
        if d > SYMMETRY_TOLERANCE:
            raise GeometryError(
                f"{field}: the body is not its own mirror image in the plane {PLANE_NAMES[axis]} " + _by(d)
            )
    if declared == "revolution":
        u, v, w = rotation[0].tolist()  # the file's axis

        def turn(image: list[tuple[int, int]]) -> None:
            occ.rotate(image, *centre.tolist(), u, v, w, _TURN)

        d = _difference(volumes, turn)
        if d > SYMMETRY_TOLERANCE:
            raise GeometryError(f"{field}: the body is not a body of revolution about its axis " + _by(d))
    return SYMMETRIES[declared]


def _by(difference: float) -> str:
    """The end of a refusal: by how much, the limit and the fix."""
    if math.isinf(difference):
        return '(OpenCASCADE could not compare it with its image); say symmetry = "auto" or "none"'
    return (
        f"({difference:.2g} of its volume lies outside its image, at most {SYMMETRY_TOLERANCE:g});"
        ' say symmetry = "auto" to use the mirror planes it has, or "none"'
    )
