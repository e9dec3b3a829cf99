"""Outer-surface quadrature of a projectile mesh (scikit-fem), computed once.

Two normal models (:data:`NORMAL_MODELS`), of the same cost per load evaluation:

``mesh``
    The facets' own points, normals and weights: flat triangles for a first-order mesh, curved ones for a
    second-order mesh.  Flat facets tilt the normals, which loads the shank where the exact surface carries
    nothing (docs/accuracy.md).
``exact``
    The facet quadrature carried onto the exact surface: by a radial projection from the axis onto the profile of
    a body of revolution (:func:`_to_exact_surface`), or through each curved CAD surface's own parametrisation
    for a projectile from a CAD file (:meth:`mesh.cad.CadSurface.quadrature`; facets on planes keep their own).

:func:`surface_quadrature` rewrites the mirror images (:func:`find_mirror_images`) of the fundamental part by
exact sign changes, so that :class:`~fem_loads.DAFLLoads` sums them exactly (docs/numerics.md, exact mirror symmetry).
"""

from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import TYPE_CHECKING

import numpy as np

from mesh.geometry import ProjectileMesh
from mesh.profile import Profile

from .exposure import DEFAULT_RESOLUTION, Exposure, exposure_table
from .mass import to_skfem

if TYPE_CHECKING:  # scikit-fem (and gmsh, by mesh.cad) is imported where it is used
    from skfem import MeshTet1, MeshTet2

    from mesh.cad import CadSurface

__all__ = ["SurfaceQuadrature", "surface_quadrature", "find_mirror_images", "with_exposure", "NORMAL_MODELS"]

# the sign of (y, z) in the four mirror images of two planes, in the order of ``mirror_images``
MIRROR_SIGNS = ((1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0))
# the images of each symmetry, by the axes of its planes (1: the plane y = 0, 2: z = 0)
SIGNS_OF_PLANES = {(1, 2): MIRROR_SIGNS, (1,): MIRROR_SIGNS[:2], (2,): (MIRROR_SIGNS[0], MIRROR_SIGNS[2])}

NORMAL_MODELS = ("mesh", "exact")
Rule = tuple[np.ndarray, np.ndarray, np.ndarray]  # a facet quadrature: points, unit normals and weights


@dataclass(frozen=True)
class SurfaceQuadrature:
    """Quadrature of the outer surface in the body frame about the centre of mass.

    Attributes
    ----------
    points : ndarray, shape (n, 3)
        Quadrature points ``r`` relative to the centre of mass (m); x forward.
    normals : ndarray, shape (n, 3)
        Outward unit normals.
    weights : ndarray, shape (n,)
        Area weights (m^2).
    mirror_images : ndarray of int, shape (k, n // k), optional
        Indices of the mirror images of each point of the fundamental part: for two mirror planes (k = 4) the
        quarter ``y > 0, z > 0``, the point itself, its images in ``y = 0``, in ``z = 0`` and in both
        (:data:`MIRROR_SIGNS`); for one plane (k = 2) the half on its positive side and its image.  Exact sign
        changes of the point and its normal, with equal weights.  None without mirror symmetry.
    exposure : Exposure, optional
        Which points the target cannot reach, by the direction they move (:mod:`fem_loads.exposure`);
        None for a convex body, whose every point with a positive ``Vn`` is reached.
    moment_arms : ndarray, shape (n, 3)
        ``r x n`` for each point, cached for the moment and the normal velocity.
    """

    points: np.ndarray
    normals: np.ndarray
    weights: np.ndarray
    mirror_images: np.ndarray | None = None
    exposure: Exposure | None = None
    moment_arms: np.ndarray = field(init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "moment_arms", np.cross(self.points, self.normals))

    @property
    def mirror_planes(self) -> tuple[int, ...]:
        """The axes of the mirror planes (1: ``y = 0``, 2: ``z = 0``) of :attr:`mirror_images`; () without."""
        return _planes(self.points, self.mirror_images)

    @property
    def mirror_signs(self) -> tuple[tuple[float, float], ...]:
        """The signs of ``(y, z)`` of each of :attr:`mirror_images`' rows."""
        return SIGNS_OF_PLANES[self.mirror_planes] if self.mirror_images is not None else ((1.0, 1.0),)

    def __len__(self) -> int:
        return len(self.weights)

    @property
    def area(self) -> float:
        """Total area (m^2)."""
        return float(self.weights.sum())

    def enclosed_volume(self) -> float:
        """Volume enclosed by the surface, ``sum (r . n) w / 3`` (m^3)."""
        return float(np.einsum("ij,ij,i->", self.points, self.normals, self.weights) / 3.0)


def _facet_indices(m: MeshTet1 | MeshTet2, triangles: np.ndarray) -> np.ndarray:
    """Indices in ``m.facets`` of the triangles given by their corner nodes."""
    n = np.int64(m.p.shape[1]) if m.p.shape[1] > 0 else np.int64(1)

    def key(tri: np.ndarray) -> np.ndarray:
        tri = np.sort(tri.astype(np.int64), axis=0)
        return (tri[0] * n + tri[1]) * n + tri[2]

    facet_keys = key(m.facets)
    order = np.argsort(facet_keys)
    wanted = key(triangles[:, :3].T)
    pos = np.searchsorted(facet_keys, wanted, sorter=order)
    found = order[np.minimum(pos, len(order) - 1)]
    if not np.array_equal(facet_keys[found], wanted):
        raise ValueError("outer surface triangles are not facets of the volume mesh")
    return found


def _to_exact_surface(points: np.ndarray, normals: np.ndarray, weights: np.ndarray, profile: Profile) -> Rule:
    """Carry a facet quadrature (mesh coordinates, tip at origin) onto the exact surface of revolution: radially
    onto the profile, its normals, the weights times the projection's Jacobian ``(r / rho) (n_mesh . e_rho) /
    (n_exact . e_rho)``."""
    s = -points[:, 0]
    rho = np.hypot(points[:, 1], points[:, 2])
    e_rho = np.zeros_like(points)
    e_rho[:, 1:] = points[:, 1:] / np.maximum(rho, np.finfo(float).tiny)[:, None]
    n_mesh_radial = np.einsum("ij,ij->i", normals, e_rho)
    # the flat tail: planar already; everything else is the lateral surface
    lateral = n_mesh_radial > 1e-6 * np.abs(normals[:, 0])
    r = profile.radius_at(s[lateral])
    n_forward, n_radial = profile.outward_normal(s[lateral])
    points, normals, weights = points.copy(), normals.copy(), weights.copy()
    points[lateral, 1:] = r[:, None] * e_rho[lateral, 1:]
    normals[lateral, 0] = n_forward
    normals[lateral, 1:] = n_radial[:, None] * e_rho[lateral, 1:]
    weights[lateral] *= (r / rho[lateral]) * n_mesh_radial[lateral] / n_radial
    # the tail disc (and a flat front face), bounded by a polygon: stretched radially onto its exact disc
    tail, front = ~lateral & (normals[:, 0] < 0), ~lateral & (normals[:, 0] > 0)
    for disc, radius in ((tail, profile.tail_radius), (front, profile.tip_radius)):
        if disc.any() and radius > 0:
            stretch = np.pi * radius**2 / weights[disc].sum()
            weights[disc] *= stretch
            points[disc, 1:] *= np.sqrt(stretch)
    return points, normals, weights


def _planes(points: np.ndarray, images: np.ndarray | None) -> tuple[int, ...]:
    """The axes of the mirror planes of the images (:attr:`SurfaceQuadrature.mirror_planes`)."""
    if images is None:
        return ()
    if len(images) == 4:
        return (1, 2)
    # the half's points lie off their plane (y > 0, or z > 0), and their images across it
    point, image = points[images[0, 0]], points[images[1, 0]]
    return (1,) if point[1] * image[1] < 0.0 else (2,)


def find_mirror_images(points: np.ndarray, rtol: float = 1e-9) -> np.ndarray | None:
    """The mirror images of each point of the fundamental part, for the most mirror planes the points have:
    both ``y = 0`` and ``z = 0``, else ``y = 0`` alone, else ``z = 0`` alone.

    Parameters
    ----------
    points : ndarray, shape (n, 3)
        Points relative to the axis ``y = z = 0``.
    rtol : float
        Largest distance between a point's image and its partner, relative to the largest coordinate.

    Returns
    -------
    ndarray of int, shape (k, n // k), or None
        :attr:`SurfaceQuadrature.mirror_images`; None unless every point has exactly one partner in each image
        of some plane (a point on a plane, or an asymmetric set).
    """
    from scipy.spatial import cKDTree  # imported where used: only when a quadrature is built

    n = len(points)
    if n == 0:
        return None
    tree = cKDTree(points)
    for planes, signs in SIGNS_OF_PLANES.items():
        part = np.flatnonzero(np.all([points[:, axis] > 0 for axis in planes], axis=0))
        if len(signs) * len(part) != n:
            continue
        images = [part]
        for sign_y, sign_z in signs[1:]:
            distance, partner = tree.query(points[part] * np.array([1.0, sign_y, sign_z]))
            if distance.max() > rtol * np.abs(points).max():
                break
            images.append(partner)
        else:
            table = np.array(images)
            if len(np.unique(table)) == n:
                return table
    return None


def _on_cad_surface(rule: Rule, mesh: ProjectileMesh, intorder: int, surface: CadSurface) -> Rule:
    """The rule of :meth:`mesh.cad.CadSurface.quadrature` on the facets of curved CAD surfaces; those on planes
    keep their own (exact) points, normals and weights."""
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTri

    points, normals, weights = (a.copy() for a in rule)
    ref_points, ref_weights = get_quadrature(RefTri, intorder)
    nodes = mesh.points[mesh.outer]  # corners, and edge nodes on the surface (on its boundary curves too)
    assert mesh.outer_entity is not None  # checked by surface_quadrature
    cad_points, cad_normals, cad_weights, planar = surface.quadrature(nodes, mesh.outer_entity, ref_points, ref_weights)
    curved = ~np.repeat(planar, len(ref_weights))
    cosine = np.einsum("ij,ij->i", cad_normals[curved], normals[curved])
    points[curved] = cad_points[curved]
    normals[curved] = cad_normals[curved] * np.sign(cosine)[:, None]  # CAD faces may face either way: outward
    weights[curved] = cad_weights[curved]
    return points, normals, weights


def _basis_rule(mesh: ProjectileMesh, intorder: int, skfem_mesh: MeshTet1 | MeshTet2 | None) -> Rule:
    """Points, unit normals and weights of the outer facets from scikit-fem's FacetBasis."""
    from skfem import ElementTetP0, FacetBasis

    m = to_skfem(mesh) if skfem_mesh is None else skfem_mesh
    corners = mesh.outer[:, :3]
    if mesh.order == 2:
        # scikit-fem renumbers the corner nodes of a quadratic mesh first, in sorted order
        corners = np.searchsorted(np.unique(mesh.tetra[:, :4]), corners)
    fb = FacetBasis(m, ElementTetP0(), facets=_facet_indices(m, corners), intorder=intorder)
    points = np.asarray(fb.global_coordinates()).reshape(3, -1).T
    normals = np.asarray(fb.normals).reshape(3, -1).T
    return points, normals / np.linalg.norm(normals, axis=1)[:, None], fb.dx.reshape(-1)


def _shape_rule(mesh: ProjectileMesh, intorder: int) -> Rule:
    """The rule of :func:`_basis_rule` from the facets' own Lagrange shape functions, without FacetBasis's Newton
    inversion of every point into its tetrahedron, which fails on some curved elements (kinnala/scikit-fem#965)."""
    from skfem import ElementTriP1, ElementTriP2
    from skfem.quadrature import get_quadrature
    from skfem.refdom import RefTri

    ref_points, ref_weights = get_quadrature(RefTri, intorder)
    element = ElementTriP2() if mesh.order == 2 else ElementTriP1()
    nodes = mesh.points[mesh.outer]  # (n, k, 3)
    shapes = [element.lbasis(ref_points, i) for i in range(nodes.shape[1])]
    phi = np.array([value for value, _ in shapes])  # (k, q)
    dphi = np.array([gradient for _, gradient in shapes])  # (k, 2, q)
    points = np.einsum("kq,nkd->nqd", phi, nodes)
    tangents = np.einsum("kjq,nkd->nqjd", dphi, nodes)
    cross = np.cross(tangents[:, :, 0], tangents[:, :, 1])
    area = np.linalg.norm(cross, axis=2)
    return (points.reshape(-1, 3), (cross / area[..., None]).reshape(-1, 3), (ref_weights[None, :] * area).reshape(-1))


def surface_quadrature(
    mesh: ProjectileMesh,
    centre: np.ndarray,
    profile: Profile | None = None,
    normal_model: str = "exact",
    intorder: int = 2,
    skfem_mesh: MeshTet1 | MeshTet2 | None = None,
    surface: CadSurface | None = None,
    facet_rule: str = "basis",
) -> SurfaceQuadrature:
    """Quadrature points, outward normals and weights of the outer surface.

    Parameters
    ----------
    mesh : ProjectileMesh
        The projectile mesh (its ``outer`` triangles select the facets).
    centre : ndarray, shape (3,)
        Centre of mass in mesh coordinates (m); the result is relative to it.
    profile : Profile, optional
        The exact outer profile; ``normal_model="exact"`` needs it or ``surface``.
    normal_model : {"exact", "mesh"}
        See the module docstring.
    intorder : int
        Polynomial degree integrated exactly on each facet.
    skfem_mesh : MeshTet1 or MeshTet2, optional
        A scikit-fem mesh already made from ``mesh``.
    surface : mesh.cad.CadSurface, optional
        The exact surface of a projectile from a CAD file, for ``normal_model="exact"`` (``mesh.outer_entity``
        names each facet's CAD surface).
    facet_rule : {"basis", "shape"}
        How the facets' own points, normals and weights are computed: by scikit-fem's :class:`~skfem.FacetBasis` (the
        analytic projectiles' meshes), or from the facets' Lagrange shape functions (:func:`_shape_rule`; any mesh).
    """
    if facet_rule not in ("basis", "shape"):
        raise ValueError(f"facet_rule = {facet_rule!r}: must be 'basis' or 'shape'")
    if normal_model not in NORMAL_MODELS:
        raise ValueError(f"normal_model = {normal_model!r}: must be one of {NORMAL_MODELS}")
    if normal_model == "exact" and profile is None and (surface is None or mesh.outer_entity is None):
        raise ValueError("normal_model = 'exact' needs the profile or the CAD surface")
    rule = _basis_rule(mesh, intorder, skfem_mesh) if facet_rule == "basis" else _shape_rule(mesh, intorder)
    if normal_model == "exact" and profile is not None:
        rule = _to_exact_surface(*rule, profile)
    elif normal_model == "exact":
        assert surface is not None  # checked above
        rule = _on_cad_surface(rule, mesh, intorder, surface)
    points, normals, weights = (np.ascontiguousarray(a) for a in (rule[0] - centre, *rule[1:]))
    images = find_mirror_images(points)
    if images is not None:  # the images rewritten from the part; each point keeps its facet (the renderer's)
        for partner, (sign_y, sign_z) in zip(images[1:], SIGNS_OF_PLANES[_planes(points, images)][1:]):
            flip = np.array([1.0, sign_y, sign_z])
            points[partner] = points[images[0]] * flip
            normals[partner] = normals[images[0]] * flip
            weights[partner] = weights[images[0]]
    return SurfaceQuadrature(points, normals, weights, images)


def with_exposure(
    quadrature: SurfaceQuadrature,
    triangles: np.ndarray,
    lift: float,
    resolution: int = DEFAULT_RESOLUTION,
    least_lift: float | None = None,
) -> SurfaceQuadrature:
    """``quadrature`` with the exposure of its points (:mod:`fem_loads.exposure`): a table for each point of its
    fundamental part (or each point) that the body can hide, none for a convex body.

    Parameters
    ----------
    triangles : ndarray, shape (t, 3, 3)
        The outer surface as flat triangles, in the quadrature's frame (about the centre of mass, m).
    lift, least_lift : float, optional
        How far off the surface the rays start at most and at least (m); see :func:`~.exposure.exposure_table`.
    """
    part = quadrature.mirror_images[0] if quadrature.mirror_images is not None else np.arange(len(quadrature))
    tables = exposure_table(quadrature.points[part], quadrature.normals[part], triangles, lift, resolution, least_lift)
    return replace(quadrature, exposure=Exposure(*tables) if len(tables[0]) else None)  # no columns: convex
