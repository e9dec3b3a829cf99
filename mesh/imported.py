"""Projectiles from files: CAD solids (STEP, BREP, IGES) meshed by gmsh, and volume meshes read by meshio.

A file's projectile is any closed body, wherever the file puts it.  Its axis
is the line along the scene's ``axis`` (or, with ``"auto"``, the principal axis
of least inertia) through the body's centroid (:func:`place`).  Its coordinates
are moved so that this line passes through the origin, scaled from the file's
length unit to metres and rotated so that the axis runs along +x, tail to tip;
the mesh keeps that *model frame* (the tip is wherever the file put it along
the axis), and :func:`body_frame` moves the origin to the tip (the body's
largest x, on the axis ``y = z = 0``), as the analytic projectiles have it.

Every tetrahedron carries a region: :data:`~mesh.geometry.BODY`, or
``MATERIAL_BASE + k`` for the ``k``-th of the named materials (a CAD solid's
name, ``solid1``, ``solid2``, ... in the file's order, or a mesh's physical
group or cell-data value).  The outer surface is the boundary shell that holds
the body's outermost point; the shells of closed internal voids are not
exposed to the target and are left out.  For a CAD file each outer triangle
keeps its CAD surface (``ProjectileMesh.outer_entity``), so that
:class:`mesh.cad.CadSurface` can integrate over the exact surface.  The
readers are :mod:`mesh.cad` and :mod:`mesh.volume_mesh`; this module holds what
they share.
"""

from __future__ import annotations

import hashlib
import math
import os
from collections.abc import Callable, Mapping
from dataclasses import dataclass, replace
from pathlib import Path
from typing import TypeVar

import numpy as np

from .geometry import BODY, TRI_EDGES, ProjectileMesh, _permute

__all__ = [
    "FileGeometry",
    "GeometryError",
    "body_frame",
    "outline",
    "BodyOutline",
    "UNITS",
    "CAD_SUFFIXES",
    "MATERIAL_BASE",
    "file_digest",
    "place",
    "AXIS_TOLERANCE",
]

UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
CAD_SUFFIXES = {".step": "step", ".stp": "step", ".brep": "brep", ".brp": "brep", ".iges": "iges", ".igs": "iges"}
MATERIAL_BASE = 10  # region tag of the first named material
# the sizes a projectile can have (m, its largest extent): a body outside them is in the wrong unit
SMALLEST_BODY, LARGEST_BODY = 0.002, 50.0
TYPICAL_BODY = 0.3  # m
DECLARED = {"metres": "m", "centimetres": "cm", "millimetres": "mm", "inches": "in"}
#: deg: a body whose axis of least inertia lies further than this from the axis it is read along is warned of,
#: or refused when the scene gives no axis
AXIS_TOLERANCE = 1.0
#: a body has a long axis when its smallest principal moment of inertia is below this share of the next
LONG_AXIS = 0.9
#: its tip is clear when one end lies this share of its length further from its centroid than the other
CLEAR_TIP = 0.02
#: a centroid this close to the file's own line (a share of the body's length) lies on it: the body was drawn about
#: that line (an eroded nose's centroid lies off its shank's axis by 1e-6 to 1e-4 of its length), and planes cut
#: through it, not a hair beside the edges drawn on it (which leaves slivers that gmsh cannot mesh)
ON_LINE = 1e-3


class GeometryError(ValueError):
    """A file that does not describe one closed projectile; the message names the fix."""


def file_digest(path: str | os.PathLike[str]) -> str:
    """SHA-256 of a file's bytes: what a cached mesh of it depends on."""
    return hashlib.sha256(Path(path).read_bytes()).hexdigest()


@dataclass(frozen=True)
class FileGeometry:
    """A projectile read from a CAD or mesh file.

    Attributes
    ----------
    path : str
        The file (absolute).
    digest : str
        :func:`file_digest` of its contents (a changed file is meshed again).
    unit : str
        The length unit of the file's numbers: a key of :data:`UNITS`.
    axis : tuple of float, "auto" or None
        The file's direction from tail to tip (rotated onto +x); ``"auto"``: the body's axis of least
        inertia; None: +x, checked against the body (:func:`place` resolves the last two).
    materials : tuple of str
        Names of the solids or groups that have their own density, in the order of
        their region tags (``MATERIAL_BASE``, ``MATERIAL_BASE + 1``, ...).
    cell_field : str or None
        For a mesh file: the cell-data field whose values name the materials
        (default: the physical groups).
    symmetry : str
        The mirror planes a CAD body is meshed by (:data:`mesh.symmetry.SYMMETRIES`): ``"auto"``
        (those it has), ``"none"``, or one it is declared to have and is checked for.
    origin : tuple of float or None
        A point of the axis in the file's coordinates and unit (the body's centroid, moved along the
        axis to the file's origin's foot); None until :func:`place` finds it.
    """

    path: str
    digest: str
    unit: str = "m"
    axis: tuple[float, float, float] | str | None = None
    materials: tuple[str, ...] = ()
    cell_field: str | None = None
    symmetry: str = "auto"
    origin: tuple[float, float, float] | None = None

    @property
    def is_cad(self) -> bool:
        return Path(self.path).suffix.lower() in CAD_SUFFIXES

    @property
    def placed(self) -> bool:
        """Whether the axis and origin are known (:func:`place`)."""
        return self.origin is not None and isinstance(self.axis, tuple)

    @property
    def rotation(self) -> np.ndarray:
        """The rotation from the file's directions to the model frame's: its rows are the model frame's axes in
        the file's coordinates (the first the axis)."""
        assert isinstance(self.axis, tuple), "place() the geometry first"
        return rotation_to_x(self.axis)

    @property
    def centre(self) -> np.ndarray:
        """A point of the axis in the file's coordinates and unit (:attr:`origin`)."""
        assert self.origin is not None, "place() the geometry first"
        return np.asarray(self.origin, dtype=float)


@dataclass(frozen=True)
class BodyOutline:
    """The sizes of a body measured on its mesh (m): what the analytic profiles state."""

    length: float
    diameter: float
    nose_length: float


def rotation_to_x(axis: tuple[float, float, float]) -> np.ndarray:
    """The rotation matrix that turns ``axis`` onto +x (the shortest turn; a half turn about z for -x)."""
    a = np.asarray(axis, dtype=float)
    a = a / np.linalg.norm(a)
    x = np.array([1.0, 0.0, 0.0])
    k = np.cross(a, x)
    s, c = np.linalg.norm(k), float(a @ x)
    if s < 1e-15:
        return np.eye(3) if c > 0 else np.diag([-1.0, -1.0, 1.0])
    k = k / s
    kx = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * kx + (1.0 - c) * kx @ kx


def check_size(extent: float, geometry: FileGeometry, declared: str | None = None) -> None:
    """Refuse a body whose largest extent says the unit is wrong."""
    if SMALLEST_BODY <= extent <= LARGEST_BODY:
        return
    raw = extent / UNITS[geometry.unit]
    # the unit that makes the body most like a projectile (a few decimetres); the file's own if it fits
    own = DECLARED.get(declared) if declared is not None else None
    fits = sorted(
        (u for u, f in UNITS.items() if SMALLEST_BODY <= raw * f <= LARGEST_BODY),
        key=lambda u: (u != own, abs(math.log(raw * UNITS[u] / TYPICAL_BODY))),
    )
    hint = f'; if the file is in {fits[0]}, say unit = "{fits[0]}"' if fits else ""
    told = f" (the file declares {declared})" if declared else ""
    raise GeometryError(
        f'projectile.geometry.unit = "{geometry.unit}": the body is {extent:.4g} m across,'
        f" {'over' if extent > LARGEST_BODY else 'under'} the {SMALLEST_BODY:g}-{LARGEST_BODY:g} m"
        f" a projectile can be{told}{hint}"
    )


def components(n: int, pairs: list[tuple[int, int]]) -> np.ndarray:
    """Connected component of each of ``n`` nodes joined by ``pairs``."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    if not pairs:
        return np.arange(n)
    i, j = np.array(pairs).T
    graph = coo_matrix((np.ones(len(i)), (i, j)), shape=(n, n))
    return connected_components(graph, directed=False)[1]


def model_frame(points: np.ndarray, geometry: FileGeometry) -> np.ndarray:
    """File coordinates in metres, moved so that the axis passes through the origin and turned so that it is +x."""
    return np.ascontiguousarray(((points - geometry.centre) * UNITS[geometry.unit]) @ geometry.rotation.T)


def place(
    geometry: FileGeometry,
    centroid: np.ndarray,
    inertia: np.ndarray,
    span: Callable[[np.ndarray], tuple[float, float]],
) -> FileGeometry:
    """``geometry`` with its axis and origin found from the body, wherever the file puts it.

    Parameters
    ----------
    geometry : FileGeometry
        As the scene gives it.
    centroid : ndarray, shape (3,)
        The body's centroid (the file's coordinates and unit).
    inertia : ndarray, shape (3, 3)
        Its inertia tensor of unit density about the centroid (any unit: only its axes and ratios count).
    span : callable
        ``span(direction)``: the lowest and highest projections of the body onto a unit direction.

    Returns
    -------
    FileGeometry
        With ``axis`` a direction (the given one; with ``"auto"`` the axis of least inertia, tip at the
        end further from the centroid, which is the smaller end of a body whose sections shrink
        towards it; with None +x) and ``origin`` the centroid, moved along the axis to the foot of
        the file's origin.  A centroid within :data:`ON_LINE` of the body's length of the file's own
        line (the axis through the file's origin) is taken as on it: a body drawn about its axis at the
        origin is meshed exactly as the file draws it.

    Raises
    ------
    GeometryError
        ``"auto"`` for a body without a clear long axis or tip; no axis given for a body whose axis of
        least inertia lies more than :data:`AXIS_TOLERANCE` from +x, or whose tip is clearly at -x.
    """
    moments, axes = np.linalg.eigh(inertia)
    least = axes[:, 0]
    long_axis = moments[0] < LONG_AXIS * moments[1]

    def tip_end(direction: np.ndarray) -> float:
        """Which way the tip lies along ``direction``: > 0 forwards, < 0 backwards, 0 unclear."""
        low, high = span(direction)
        at = float(centroid @ direction)
        lean = (high - at) - (at - low)
        return lean if abs(lean) > CLEAR_TIP * (high - low) else 0.0

    axis = geometry.axis
    if axis == "auto":
        if not long_axis:
            raise GeometryError(
                f'projectile.geometry.axis = "auto": the body has no clear long axis (principal moments of'
                f" inertia {moments[0]:.3g}, {moments[1]:.3g}, {moments[2]:.3g}: the least within"
                f" {1 - LONG_AXIS:.0%} of the next); give the axis from tail to tip, axis = [x, y, z]"
            )
        lean = tip_end(least)
        if lean == 0.0:
            raise GeometryError(
                f'projectile.geometry.axis = "auto": the body\'s ends along its long axis {_direction(least)} lie'
                f" equally far from its centroid, so its tip cannot be told from its tail; give axis ="
                f" {_direction(least)} or its opposite, from tail to tip"
            )
        chosen = _snapped(least if lean > 0 else -least)
    elif axis is None:
        x = np.array([1.0, 0.0, 0.0])
        angle = math.degrees(math.acos(min(1.0, abs(float(least @ x)))))
        if long_axis and angle > AXIS_TOLERANCE:
            turned = least if tip_end(least) >= 0 else -least
            raise GeometryError(
                f"projectile.geometry.axis: not given, so the body is read along +x, but its long axis (of least"
                f" inertia) lies {angle:.1f} deg from it, along {_direction(turned)} in the file: say axis ="
                f' {_direction(turned)} (tail to tip), or axis = "auto"'
            )
        if tip_end(x) < 0:
            raise GeometryError(
                "projectile.geometry.axis: not given, so the body is read along +x, but its tip (the end further"
                ' from its centroid) is at its -x end: say axis = [-1, 0, 0], or axis = "auto"'
            )
        chosen = x
    else:
        chosen = np.asarray(axis, dtype=float)
    unit = chosen / np.linalg.norm(chosen)
    frame = replace(geometry, axis=(float(unit[0]), float(unit[1]), float(unit[2])), origin=(0.0, 0.0, 0.0))
    across = frame.rotation @ np.asarray(centroid, dtype=float)
    across[0] = 0.0  # the axial place is the tip's, found on the mesh (body_frame)
    low, high = span(frame.rotation[0])
    across[np.abs(across) <= ON_LINE * (high - low)] = 0.0
    origin = frame.rotation.T @ across
    return replace(frame, origin=(float(origin[0]), float(origin[1]), float(origin[2])))


def _snapped(direction: np.ndarray) -> np.ndarray:
    """A direction within rounding of a coordinate axis, put on it: the body is then turned exactly."""
    small = np.abs(direction) < 1e-9
    return direction if small.all() else np.where(small, 0.0, direction)


def _direction(vector: np.ndarray) -> str:
    """A direction as a scene would write it."""
    return "[" + ", ".join(f"{v:.4g}" if abs(v) > 5e-5 else "0" for v in vector.tolist()) + "]"


Key = TypeVar("Key")  # what names a solid: a volume tag (CAD), a group's name (a volume mesh)


def regions(geometry: FileGeometry, names: Mapping[Key, str]) -> dict[Key, int]:
    """Region tag of each solid (or group): its material's, else BODY."""
    found = set(names.values())
    for material in geometry.materials:
        if material not in found:
            raise GeometryError(
                f"projectile.materials.{material}: no solid or group of that name in the file"
                f" (it has: {', '.join(sorted(found))})"
            )
    index = {m: MATERIAL_BASE + k for k, m in enumerate(geometry.materials)}
    return {key: index.get(name, BODY) for key, name in names.items()}


# the faces of a tetrahedron as local corner triples, each with the corner opposite it
TET_FACES = ((1, 2, 3, 0), (0, 3, 2, 1), (0, 1, 3, 2), (0, 2, 1, 3))


def face_table(tetra: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Every face of every tetrahedron: sorted corner keys, the face's local corners and the opposite corner."""
    faces = np.array([f[:3] for f in TET_FACES])
    corners = tetra[:, :4][:, faces]  # (n, 4, 3)
    opposite = tetra[:, [f[3] for f in TET_FACES]]  # (n, 4)
    return np.sort(corners, axis=2).reshape(-1, 3), corners.reshape(-1, 3), opposite.reshape(-1)


def orient_by_volume(points: np.ndarray, tris: np.ndarray, tetra: np.ndarray) -> np.ndarray:
    """Orient boundary triangles outward: away from the corner of their tetrahedron opposite them."""
    keys, _, opposite = face_table(tetra)
    lookup = {tuple(k): o for k, o in zip(keys.tolist(), opposite.tolist())}
    inside = np.array([lookup[tuple(k)] for k in np.sort(tris[:, :3], axis=1).tolist()])
    p = points[tris[:, :3]]
    normal = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    flipped = np.einsum("ij,ij->i", normal, p[:, 0] - points[inside]) < 0
    tris = tris.copy()
    tris[flipped] = _permute(tris[flipped], (0, 2, 1), TRI_EDGES)
    return tris


def body_frame(mesh: ProjectileMesh) -> tuple[ProjectileMesh, float]:
    """The mesh moved so that its tip (its largest x, on the axis) is the origin, and that largest x (m)."""
    tip = float(mesh.points[:, 0].max())
    points = mesh.points.copy()
    points[:, 0] -= tip
    return replace(mesh, points=points), tip


def outline(mesh: ProjectileMesh) -> BodyOutline:
    """Length, diameter and nose length of a body-frame mesh (tip at the origin).

    The diameter is twice the outer surface's largest distance from the axis.  The nose ends where that distance,
    taken over the surface from the tip back, first reaches 99.9 % of the value it then holds over the next
    diameter of length (at that station) or two surface edges, whichever is longer: the shoulder where the body
    stops widening, not fins or a flare further back.
    """
    outer = mesh.outer[:, :3]
    nodes = mesh.points[np.unique(outer)]
    behind = -nodes[:, 0]
    order = np.argsort(behind, kind="stable")
    behind = behind[order]
    widest_so_far = np.maximum.accumulate(np.hypot(nodes[order, 1], nodes[order, 2]))
    corners = mesh.points[outer]
    edge = float(np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max())
    reach = np.maximum(2.0 * widest_so_far, 2.0 * edge)
    # the widest radius within the reach behind each node, and the first node already within 0.1 % of it
    ahead = widest_so_far[np.searchsorted(behind, behind + reach, side="right") - 1]
    shoulder = int(np.argmax(widest_so_far >= 0.999 * ahead))
    return BodyOutline(
        length=float(behind[-1]),
        diameter=float(2.0 * widest_so_far[-1]),
        nose_length=float(behind[shoulder]),
    )
