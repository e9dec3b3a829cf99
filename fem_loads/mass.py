"""Mass, centre of mass and inertia tensor of a multi-material solid mesh (scikit-fem).

Over a mesh that is its own mirror image (:func:`mirror_symmetric_axes`) the integrals of the odd monomials
(``y``, ``x y``, ``y z``, ...) are set to zero: their round-off would tilt the principal axes and break the
mirror symmetry of the motion.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:  # scikit-fem is imported where it is used: a run from cached data never needs it
    from skfem import MeshTet1, MeshTet2

from mesh.geometry import ProjectileMesh

__all__ = ["MassProperties", "to_skfem", "mass_properties", "mirror_symmetric_axes"]


@dataclass(frozen=True)
class MassProperties:
    """Rigid-body mass properties in the body frame.

    Attributes
    ----------
    mass : float
        Mass (kg).
    centre : ndarray, shape (3,)
        Centre of mass in mesh coordinates (m; tip at the origin, x forward).
    inertia : ndarray, shape (3, 3)
        Inertia tensor about the centre of mass, body axes (kg m^2).
    volume : float
        Volume of material (m^3).
    """

    mass: float
    centre: np.ndarray
    inertia: np.ndarray
    volume: float

    @property
    def centre_from_tip(self) -> float:
        """Distance of the centre of mass behind the nose tip (m)."""
        return float(-self.centre[0])

    @property
    def axial_inertia(self) -> float:
        """Moment of inertia about the projectile axis (kg m^2)."""
        return float(self.inertia[0, 0])

    @property
    def transverse_inertia(self) -> float:
        """Mean moment of inertia about the two transverse body axes (kg m^2)."""
        return float(0.5 * (self.inertia[1, 1] + self.inertia[2, 2]))

    def with_transverse_scale(self, scale: float) -> MassProperties:
        """The same body with both transverse moments of inertia scaled by ``scale``."""
        inertia = self.inertia.copy()
        inertia[1:, 1:] *= scale
        return MassProperties(self.mass, self.centre, inertia, self.volume)

    @classmethod
    def axisymmetric(
        cls, mass: float, centre_from_tip: float, axial_inertia: float, transverse_inertia: float
    ) -> MassProperties:
        """Mass properties given directly (no mesh integration, so no volume: NaN)."""
        inertia = np.diag([axial_inertia, transverse_inertia, transverse_inertia])
        return cls(mass, np.array([-centre_from_tip, 0.0, 0.0]), inertia, float("nan"))


def to_skfem(mesh: ProjectileMesh) -> MeshTet1 | MeshTet2:
    """The scikit-fem mesh of a :class:`ProjectileMesh` (corner order kept)."""
    from skfem import MeshTet1, MeshTet2

    kind = MeshTet1 if mesh.order == 1 else MeshTet2
    return kind(np.ascontiguousarray(mesh.points.T), np.ascontiguousarray(mesh.tetra.T))


# the monomials up to degree two, integrated per element: 1, x, y, z, x^2, y^2, z^2, x y, x z, y z
_MONOMIALS = (
    lambda x: 1.0 + 0.0 * x[0],
    *(lambda x, a=a: x[a] for a in range(3)),
    *(lambda x, a=a, b=b: x[a] * x[b] for a, b in ((0, 0), (1, 1), (2, 2), (0, 1), (0, 2), (1, 2))),
)


def mirror_symmetric_axes(mesh: ProjectileMesh) -> tuple[int, ...]:
    """The axes (1 for ``y``, 2 for ``z``) in whose plane ``x[axis] = 0`` the mesh is its own mirror image, bitwise:
    every node's image is a node, and the image of every element is an element of the same region."""
    points = mesh.points + 0.0  # -0.0 -> 0.0, so that the comparison is of values
    elements = np.column_stack([np.sort(mesh.tetra[:, :4], axis=1), mesh.tetra_region])
    elements = elements[np.lexsort(elements.T[::-1])]
    axes = []
    for axis in (1, 2):
        image = points.copy()
        image[:, axis] = -image[:, axis] + 0.0
        order, image_order = np.lexsort(points.T[::-1]), np.lexsort(image.T[::-1])
        if not np.array_equal(points[order], image[image_order]):
            continue
        partner = np.empty(len(points), dtype=np.int64)
        partner[image_order] = order  # the image of node image_order[k] is node order[k]
        mirrored = np.column_stack([np.sort(partner[mesh.tetra[:, :4]], axis=1), mesh.tetra_region])
        if np.array_equal(elements, mirrored[np.lexsort(mirrored.T[::-1])]):
            axes.append(axis)
    return tuple(axes)


def mass_properties(
    mesh: ProjectileMesh, densities: dict[int, float], skfem_mesh: MeshTet1 | MeshTet2 | None = None
) -> MassProperties:
    """Integrate the mass properties of a multi-material mesh.

    Parameters
    ----------
    mesh : ProjectileMesh
        The mesh; ``mesh.tetra_region`` holds each element's region tag.
    densities : dict
        Density (kg/m^3) of each region tag present in the mesh.
    skfem_mesh : MeshTet1 or MeshTet2, optional
        A scikit-fem mesh already made from ``mesh``.
    """
    if missing := set(np.unique(mesh.tetra_region).tolist()) - set(densities):
        raise ValueError(f"densities: no density given for region(s) {sorted(missing)}")
    from skfem import Basis, ElementTetP0, Functional

    m = to_skfem(mesh) if skfem_mesh is None else skfem_mesh
    # degree-2 integrands on a quadratic map need a higher rule: x^2 detJ has degree 2*2 + 3
    basis = Basis(m, ElementTetP0(), intorder=2 if mesh.order == 1 else 7)
    rho = np.array([densities[r] for r in mesh.tetra_region.tolist()])
    per_element = np.array([Functional(lambda w, f=f: f(w.x)).elemental(basis) for f in _MONOMIALS])
    volume = float(per_element[0].sum())
    v, sx, sy, sz, xx, yy, zz, xy, xz, yz = per_element @ rho
    symmetric = mirror_symmetric_axes(mesh)
    if 1 in symmetric:  # odd in y
        sy = xy = yz = 0.0
    if 2 in symmetric:  # odd in z
        sz = xz = yz = 0.0
    centre = np.array([sx, sy, sz]) / v
    second = np.array([[xx, xy, xz], [xy, yy, yz], [xz, yz, zz]])
    # inertia about the origin, shifted to the centre of mass (parallel-axis theorem)
    inertia = np.trace(second) * np.eye(3) - second - v * (centre @ centre * np.eye(3) - np.outer(centre, centre))
    return MassProperties(float(v), centre, inertia, volume)
