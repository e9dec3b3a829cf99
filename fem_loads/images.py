"""Sums over a mirror-symmetric quadrature that keep a symmetric state exactly symmetric.

The quadrature of a projectile mesh is mirror symmetric bitwise about the body
planes ``y = 0`` and ``z = 0`` (:func:`fem_loads.quadrature.mirror_quarters`):
each point of the quarter ``y > 0, z > 0`` has three images whose coordinates
and normals differ from its own only in signs.  :class:`MirrorImages` keeps
the quarter's columns of ``[n | r x n]`` and evaluates every per-point
quantity as four rows, one per image, shape ``(4, m)`` with ``m = n / 4``:

* ``Vn`` of image ``k`` is the quarter's ``[n | r x n]`` times the generalised
  velocity ``(R^T V, omega)`` with the image's signs, all four in one product;
* the resultant is ``P = [n | r x n] S^T``, shape ``(6, 4)``, folded as
  ``(P0 + Y P1) + Z (P2 + Y P3)`` per row, where ``Y`` and ``Z`` are the signs
  the two mirrors give that component.

Why: a state symmetric about a body plane (a straight normal impact, or the
mirror image of another run) then has bitwise-equal stresses on mirrored
images, the differences in the fold are exactly zero, and the components the
mirror reverses vanish exactly, whatever the order in which BLAS sums.  A
plain sum over all points cancels only to round-off (~1e-16 relative), which
the jump of the stress at ``Vn = 0`` on the shank amplifies into a lateral
drift of millimetres over a long run (docs/numerics.md, Hard cases).

It relies on a property of the BLAS matrix product: equal rows of one factor
give bitwise-equal rows of the result (each output element is computed by the
same sequence of operations).  It holds for OpenBLAS's kernels and is checked
on the actual arrays when the images are set up; if it fails, each image is
evaluated by its own matrix-vector product, which is exact but slower.
"""

from __future__ import annotations

import numpy as np

from .quadrature import MIRROR_SIGNS

__all__ = ["MirrorImages"]

# the sign each image gives the components of (V_body, omega), i.e. of the rows of [n | r x n]:
# a mirror in y = 0 reverses n_y, (r x n)_x and (r x n)_z; one in z = 0 reverses n_z, (r x n)_x, (r x n)_y
IMAGE_SIGNS = np.array([[1.0, sy, sz, sy * sz, sz, sy] for sy, sz in MIRROR_SIGNS])
POINT_SIGNS = np.array([[1.0, sy, sz] for sy, sz in MIRROR_SIGNS])
if [tuple(s) for s in MIRROR_SIGNS] != [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)]:
    raise ImportError("MirrorImages folds the images in the order (+, +), (-, +), (+, -), (-, -)")
_Y = IMAGE_SIGNS[1].tolist()  # the y mirror's sign of each row
_Z = IMAGE_SIGNS[2].tolist()  # the z mirror's sign of each row


def _generic_factors(count: int, start: int) -> np.ndarray:
    """``count`` numbers spread over [-1, 1) with full mantissas: the fractional parts of the multiples
    ``start + 1, start + 2, ...`` of the golden ratio.  Factors for the check below that need no
    ``numpy.random`` (importing it took 4-8 ms of every run's start)."""
    return 2.0 * ((np.arange(start + 1, start + count + 1) * 0.6180339887498949) % 1.0) - 1.0


def _products_reproducible(arm: np.ndarray, points: np.ndarray) -> bool:
    """Whether equal images give bitwise-equal results in the matrix products used here.

    Checked on four equal copies of the quarter's arrays (the layout of the
    images' arrays) with generic factors (:func:`_generic_factors`).
    """
    m = arm.shape[1]
    normal_velocity = _generic_factors(6, 0) @ np.tile(arm, 4)
    heights = _generic_factors(3, 6) @ np.tile(points, 4)
    resultant = arm @ np.tile(_generic_factors(m, 9), (4, 1)).T
    return all(
        np.array_equal(a[0], a[k])
        for a in (normal_velocity.reshape(4, m), heights.reshape(4, m), resultant.T)
        for k in (1, 2, 3)
    )


class MirrorImages:
    """The four mirror images of a quadrature's quarter, and exact sums over them.

    Parameters
    ----------
    images : ndarray of int, shape (4, m)
        ``SurfaceQuadrature.mirror_quarters``: the quarter's points and their
        images in ``y = 0``, ``z = 0`` and both.
    normal_arm_t : ndarray, shape (6, n)
        ``[n | r x n]`` of every point, transposed.
    points_t : ndarray, shape (3, n)
        The points, transposed (m).
    """

    def __init__(self, images: np.ndarray, normal_arm_t: np.ndarray, points_t: np.ndarray) -> None:
        self.images = images
        quarter = images[0]
        self.normal_arm = np.ascontiguousarray(normal_arm_t[:, quarter])
        self.points = np.ascontiguousarray(points_t[:, quarter])
        self.shape = images.shape
        # the images' [n | r x n] and points side by side, shape (6, n) and (3, n): exact sign changes
        # of the quarter's, so that one product gives the four images' rows
        self.image_normal_arm = np.hstack([self.normal_arm * signs[:, None] for signs in IMAGE_SIGNS])
        self.image_points = np.hstack([self.points * signs[:, None] for signs in POINT_SIGNS])
        self.reproducible = _products_reproducible(self.normal_arm, self.points)
        self._products = np.empty((6, 4))

    def quarter(self, values: np.ndarray) -> np.ndarray:
        """Per-point values that the four images share (weights), as the images' rows, shape (4, m).

        The quarter's values repeated: elementwise passes over (4, m) arrays then need no broadcasting.
        """
        return np.tile(values[self.images[0]], (4, 1))

    def gather(self, values: np.ndarray) -> np.ndarray:
        """Per-point values, shape (n,), as the four images' rows, shape (4, m)."""
        return values[self.images]

    def scatter(self, rows: np.ndarray) -> np.ndarray:
        """The four images' rows, shape (4, m), as per-point values in the quadrature's order."""
        values = np.empty(self.images.size)
        values[self.images.ravel()] = rows.ravel()
        return values

    def normal_velocity(self, generalised: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``Vn`` of the four images, shape (4, m), for ``generalised = (R^T V, omega)``."""
        if self.reproducible:
            np.matmul(generalised, self.image_normal_arm, out=out.reshape(-1))
            return out
        for image, signs in enumerate(IMAGE_SIGNS):
            np.matmul(generalised * signs, self.normal_arm, out=out[image])
        return out

    def heights(self, height: float, up: np.ndarray, out: np.ndarray) -> np.ndarray:
        """World heights of the four images, shape (4, m): ``height + up . r`` with ``up = R[2]``."""
        if self.reproducible:
            np.matmul(up, self.image_points, out=out.reshape(-1))
        else:
            for image, signs in enumerate(POINT_SIGNS):
                np.matmul(up * signs, self.points, out=out[image])
        out += height
        return out

    def negative_resultant(self, weighted_stress: np.ndarray) -> np.ndarray:
        """``-sum s [n | r x n]`` over every point, shape (6,), from the images' rows ``s``, shape (4, m)."""
        products = self._products
        if self.reproducible:
            np.matmul(self.normal_arm, weighted_stress.T, out=products)
        else:
            for image in range(4):
                np.matmul(self.normal_arm, weighted_stress[image], out=products[:, image])
        # the fold on Python floats: four tiny numpy operations cost more than the arithmetic
        p0, p1, p2, p3 = products.T.tolist()
        return np.array([-((a + y * b) + z * (c + y * d)) for a, b, c, d, y, z in zip(p0, p1, p2, p3, _Y, _Z)])
