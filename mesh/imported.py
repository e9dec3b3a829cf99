"""Projectiles from files: CAD solids (STEP, BREP, IGES) meshed by gmsh, and volume meshes read by meshio.

A file's projectile is any closed body.  Its coordinates are scaled from the
file's length unit to metres and rotated so that the file's ``axis`` runs
along +x, tail to tip; the mesh keeps that *model frame* (the tip is wherever
the file put it), and :func:`body_frame` moves the origin to the tip (the
body's largest x, on the axis ``y = z = 0``), as the analytic projectiles
have it.

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
from collections.abc import Mapping
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
]

UNITS = {"m": 1.0, "cm": 0.01, "mm": 0.001, "in": 0.0254}
CAD_SUFFIXES = {".step": "step", ".stp": "step", ".brep": "brep", ".brp": "brep", ".iges": "iges", ".igs": "iges"}
MATERIAL_BASE = 10  # region tag of the first named material
# the sizes a projectile can have (m, its largest extent): a body outside them is in the wrong unit
SMALLEST_BODY, LARGEST_BODY = 0.002, 50.0
TYPICAL_BODY = 0.3  # m
DECLARED = {"metres": "m", "centimetres": "cm", "millimetres": "mm", "inches": "in"}


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
    axis : tuple of float
        The file's direction from tail to tip (rotated onto +x).
    materials : tuple of str
        Names of the solids or groups that have their own density, in the order of
        their region tags (``MATERIAL_BASE``, ``MATERIAL_BASE + 1``, ...).
    cell_field : str or None
        For a mesh file: the cell-data field whose values name the materials
        (default: the physical groups).
    symmetry : str
        The mirror planes a CAD body is meshed by (:data:`mesh.symmetry.SYMMETRIES`): ``"auto"``
        (those it has), ``"none"``, or one it is declared to have and is checked for.
    """

    path: str
    digest: str
    unit: str = "m"
    axis: tuple[float, float, float] = (1.0, 0.0, 0.0)
    materials: tuple[str, ...] = ()
    cell_field: str | None = None
    symmetry: str = "auto"

    @property
    def is_cad(self) -> bool:
        return Path(self.path).suffix.lower() in CAD_SUFFIXES


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
    """File coordinates in metres, turned so that the file's axis is +x."""
    return np.ascontiguousarray((points * UNITS[geometry.unit]) @ rotation_to_x(geometry.axis).T)


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

    The nose ends where the outer surface first reaches 99.9 % of its largest
    distance from the axis.
    """
    nodes = mesh.points[np.unique(mesh.outer[:, :3])]
    radius = np.hypot(nodes[:, 1], nodes[:, 2])
    widest = radius.max()
    return BodyOutline(
        length=float(-nodes[:, 0].min()),
        diameter=float(2.0 * widest),
        nose_length=float(-nodes[radius >= 0.999 * widest, 0].max()),
    )
