"""Sums over a mirror-symmetric quadrature that keep a symmetric state exactly symmetric.

Each point of the fundamental part of a mirror-symmetric quadrature (:attr:`SurfaceQuadrature.mirror_images`) has
one or three images whose coordinates and normals differ from its own only in signs.  :class:`MirrorImages`
keeps the part's columns of ``[n | r x n]`` and evaluates every per-point quantity as ``k`` rows, one per image,
shape ``(k, m)``, and folds the resultant image by image (:meth:`MirrorImages.negative_resultant`): a state
symmetric about a body plane then has bitwise-equal stresses on mirrored images and the components the mirror
reverses vanish exactly, where a plain sum cancels only to round-off, which the jump of the stress at ``Vn = 0``
amplifies into a lateral drift.  docs/numerics.md explains the products and the fold, and the check (on the actual
arrays) that equal rows of one factor of a BLAS product give bitwise-equal rows of the result; where it fails each
image gets its own product, exact but slower.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from .quadrature import MIRROR_SIGNS

__all__ = ["MirrorImages", "image_signs", "point_signs"]


def image_signs(signs: Sequence[tuple[float, float]]) -> np.ndarray:
    """The sign each image (its ``(y, z)`` signs) gives the components of ``(V_body, omega)``, i.e. of the rows
    of ``[n | r x n]``, shape (k, 6): a mirror in ``y = 0`` reverses ``n_y``, ``(r x n)_x`` and ``(r x n)_z``;
    one in ``z = 0`` reverses ``n_z``, ``(r x n)_x`` and ``(r x n)_y``."""
    return np.array([[1.0, sy, sz, sy * sz, sz, sy] for sy, sz in signs])


def point_signs(signs: Sequence[tuple[float, float]]) -> np.ndarray:
    """The sign each image gives a point's (and a normal's) ``(x, y, z)``, shape (k, 3)."""
    return np.array([[1.0, sy, sz] for sy, sz in signs])


if [tuple(s) for s in MIRROR_SIGNS] != [(1.0, 1.0), (-1.0, 1.0), (1.0, -1.0), (-1.0, -1.0)]:
    raise ImportError("MirrorImages folds four images in the order (+, +), (-, +), (+, -), (-, -)")


def _generic_factors(count: int, start: int) -> np.ndarray:
    """``count`` numbers spread over [-1, 1) with full mantissas: the fractional parts of the multiples
    ``start + 1, start + 2, ...`` of the golden ratio (no ``numpy.random``, whose import is slow)."""
    return 2.0 * ((np.arange(start + 1, start + count + 1) * 0.6180339887498949) % 1.0) - 1.0


def _products_reproducible(arm: np.ndarray, points: np.ndarray, count: int) -> bool:
    """Whether equal images give bitwise-equal results in the matrix products used here, on ``count`` equal copies
    of the part's arrays (the layout of the images' arrays) with generic factors."""
    m = arm.shape[1]
    normal_velocity = _generic_factors(6, 0) @ np.tile(arm, count)
    heights = _generic_factors(3, 6) @ np.tile(points, count)
    resultant = arm @ np.tile(_generic_factors(m, 9), (count, 1)).T
    return all(
        np.array_equal(a[0], a[k])
        for a in (normal_velocity.reshape(count, m), heights.reshape(count, m), resultant.T)
        for k in range(1, count)
    )


class MirrorImages:
    """The mirror images of a quadrature's fundamental part, and exact sums over them.

    Parameters
    ----------
    images : ndarray of int, shape (k, m)
        ``SurfaceQuadrature.mirror_images``.
    signs : sequence of (float, float)
        ``SurfaceQuadrature.mirror_signs``: each image's signs of ``(y, z)``.
    normal_arm_t : ndarray, shape (6, n)
        ``[n | r x n]`` of every point, transposed.
    points_t : ndarray, shape (3, n)
        The points, transposed (m).
    """

    def __init__(
        self, images: np.ndarray, signs: Sequence[tuple[float, float]], normal_arm_t: np.ndarray, points_t: np.ndarray
    ) -> None:
        if len(images) not in (2, 4) or len(signs) != len(images):
            raise ValueError(f"{len(images)} images with {len(signs)} signs: the images of one or two mirrors")
        self.images = images
        self.normal_arm = np.ascontiguousarray(normal_arm_t[:, images[0]])
        self.points = np.ascontiguousarray(points_t[:, images[0]])
        self.shape = images.shape
        self.image_signs, self.point_signs = image_signs(signs), point_signs(signs)
        # the images' [n | r x n] and points side by side, shape (6, n) and (3, n): exact sign changes
        # of the part's, so that one product gives every image's rows
        self.image_normal_arm = np.hstack([self.normal_arm * row[:, None] for row in self.image_signs])
        self.image_points = np.hstack([self.points * row[:, None] for row in self.point_signs])
        self.reproducible = _products_reproducible(self.normal_arm, self.points, len(images))
        self._products = np.empty((6, len(images)))
        # the signs each mirror gives each row of the resultant, for the fold
        self._fold_signs = self.image_signs[1].tolist(), self.image_signs[2].tolist() if len(images) == 4 else []

    def quarter(self, values: np.ndarray) -> np.ndarray:
        """Per-point values that the images share (weights), as the images' rows, shape (k, m): the part's repeated."""
        return np.tile(values[self.images[0]], (len(self.images), 1))

    def scatter(self, rows: np.ndarray) -> np.ndarray:
        """The images' rows, shape (k, m), as per-point values in the quadrature's order."""
        values = np.empty(self.images.size)
        values[self.images.ravel()] = rows.ravel()
        return values

    def normal_velocity(self, generalised: np.ndarray, out: np.ndarray) -> np.ndarray:
        """``Vn`` of the images, shape (k, m), for ``generalised = (R^T V, omega)``."""
        if self.reproducible:
            np.matmul(generalised, self.image_normal_arm, out=out.reshape(-1))
        else:
            for image, signs in enumerate(self.image_signs):
                np.matmul(generalised * signs, self.normal_arm, out=out[image])
        return out

    def heights(self, height: float, up: np.ndarray, out: np.ndarray) -> np.ndarray:
        """World heights of the images, shape (k, m): ``height + up . r`` with ``up = R[2]``."""
        if self.reproducible:
            np.matmul(up, self.image_points, out=out.reshape(-1))
        else:
            for image, signs in enumerate(self.point_signs):
                np.matmul(up * signs, self.points, out=out[image])
        out += height
        return out

    def negative_resultant(self, weighted_stress: np.ndarray) -> np.ndarray:
        """``-sum s [n | r x n]`` over every point, shape (6,), from the images' rows ``s``, shape (k, m): the part's
        products ``P = [n | r x n] s^T``, shape (6, k), folded per row as ``(P0 + Y P1) + Z (P2 + Y P3)`` (two
        planes) or ``P0 + S P1`` (one), ``Y``, ``Z`` and ``S`` the signs the mirrors give that component."""
        products = self._products
        if self.reproducible:
            np.matmul(self.normal_arm, weighted_stress.T, out=products)
        else:
            for image in range(len(self.images)):
                np.matmul(self.normal_arm, weighted_stress[image], out=products[:, image])
        # the fold on Python floats: a few tiny numpy operations cost more than the arithmetic
        first, second = self._fold_signs
        if len(self.images) == 2:
            p0, p1 = products.T.tolist()
            return np.array([-(a + s * b) for a, b, s in zip(p0, p1, first)])
        p0, p1, p2, p3 = products.T.tolist()
        return np.array([-((a + y * b) + z * (c + y * d)) for a, b, c, d, y, z in zip(p0, p1, p2, p3, first, second)])
