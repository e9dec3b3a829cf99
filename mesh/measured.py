"""A nose given as a table of measured points ``(x, r)``, and the smooth curve through them.

The curve is the piecewise cubic Hermite interpolant of ``r(x)`` with Fritsch-Carlson slopes
(scipy's ``PchipInterpolator``), chosen over a cubic spline because it is *shape preserving*: on
non-decreasing data it is non-decreasing, it never overshoots a point (a spline through a measured
table with a flat stretch or a sharp shoulder rings, and a radius that dips below the shank radius or
rises above it would give the nose a bulge or a waist that the table does not have), and each piece
depends only on the neighbouring points, so one bad point spoils only its own neighbourhood.  It is
``C^1``: the radius and the slope (hence the exact normal) are continuous everywhere on the nose,
the curvature jumps at the points.  At the tip and at the shoulder the slope is scipy's one-sided three-point
estimate, set to zero
where its sign would differ from the end chord's: a finite number at the tip (a pointed nose with a
finite tip angle), and at the shoulder a table that flattens towards the shank meets it nearly
tangentially, one that does not leaves a kink there (like a secant ogive).  The error for a smooth
profile sampled every ``h`` is measured in tests/mesh/test_measured_nose.py and docs/evidence-numerics.md.

Each piece is a cubic in ``x``, hence a cubic Bezier curve with control points at the thirds of its
interval (:meth:`NoseCurve.bezier`): the mesher draws the curve *exactly* as one B-spline.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ProfileNose", "ProfileBody", "NoseCurve", "MIN_POINTS", "SHANK_RTOL"]

MIN_POINTS = 3
SHANK_RTOL = 1e-6  # the last radius may differ from the shank radius by this fraction of it (then set to it)


def _finite_pairs(
    table: ProfileNose | ProfileBody, key: str, least: int, where: str
) -> tuple[tuple[float, float], ...]:
    """``table.points`` as float pairs, set back on the (frozen) table: at least ``least``, all finite, else a
    ValueError naming ``KEY.points``."""
    try:
        points = tuple((float(x), float(r)) for x, r in table.points)
    except (TypeError, ValueError):
        raise ValueError(f"{key}.points: must be a list of [x, r] pairs of numbers (m)") from None
    object.__setattr__(table, "points", points)
    if len(points) < least:
        raise ValueError(f"{key}.points: {len(points)} points given (allowed: at least {least}{where})")
    for i, (x, r) in enumerate(points):
        if not (math.isfinite(x) and math.isfinite(r)):
            raise ValueError(f"{key}.points[{i}] = [{x}, {r}]: must be finite numbers (m)")
    return points


@dataclass(frozen=True)
class ProfileNose:
    """A nose given by measured points of its half-profile.

    Parameters
    ----------
    points : sequence of (x, r)
        Distance from the tip ``x`` (m) and radius ``r`` (m) of each point: at least
        :data:`MIN_POINTS`, all finite, the first at the tip (``x = 0, r = 0``), ``x`` strictly
        increasing, ``r`` non-decreasing; the last point is the shoulder, where the nose meets the
        shank (its radius must be the shank radius: :class:`~mesh.profile.Profile` checks it).
    """

    points: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        points = _finite_pairs(self, "nose", MIN_POINTS, "")
        if points[0] != (0.0, 0.0):
            raise ValueError(
                f"nose.points[0] = [{points[0][0]:g}, {points[0][1]:g}]: must be the tip"
                " (allowed: [0, 0], x = 0 and r = 0)"
            )
        for i in range(1, len(points)):
            (x0, r0), (x1, r1) = points[i - 1], points[i]
            if not x1 > x0:
                raise ValueError(
                    f"nose.points[{i}] = [{x1:g}, {r1:g}]: x must exceed the previous point's"
                    f" x = {x0:g} m (allowed: x strictly increasing)"
                )
            if not r1 >= r0:
                raise ValueError(
                    f"nose.points[{i}] = [{x1:g}, {r1:g}]: r must be at least the previous"
                    f" point's r = {r0:g} m (allowed: r non-decreasing)"
                )

    @property
    def length(self) -> float:
        """Nose length (m): the last point's ``x``."""
        return self.points[-1][0]

    def check_shank(self, radius: float) -> None:
        """Raise ValueError unless the last point's radius is the shank ``radius`` (m) within :data:`SHANK_RTOL`."""
        last = self.points[-1][1]
        if not abs(last - radius) <= SHANK_RTOL * radius:
            raise ValueError(
                f"nose.points[{len(self.points) - 1}]: r = {last:g} m must be the shank radius"
                f" (allowed: diameter/2 = {radius:g} m, within {SHANK_RTOL:g} of it)"
            )

    def curve(self, radius: float) -> NoseCurve:
        """The interpolating curve, its last radius set to the shank ``radius`` (m)."""
        x = np.array([p[0] for p in self.points])
        r = np.array([p[1] for p in self.points])
        r[-1] = radius
        return NoseCurve(x, r)


@dataclass(frozen=True)
class ProfileBody:
    """The body behind the nose given by measured points of its half-profile: a boat tail, a flare.

    Between the nose's shoulder and the first point the body is the shank's cylinder; from the first
    point to the tail it is the same shape-preserving cubic as a measured nose's (module docstring).

    Parameters
    ----------
    points : sequence of (x, r)
        Distance from the tip ``x`` (m) and radius ``r`` (m) of each point: at least 2, all finite, ``x``
        strictly increasing, ``r > 0``; the first on the shank (its radius the shank radius, ``x`` at or
        behind the nose's end), the last at the tail (``x`` the projectile's length):
        :class:`~mesh.profile.Profile` checks those two.
    """

    points: tuple[tuple[float, float], ...]

    def __post_init__(self) -> None:
        points = _finite_pairs(self, "body", 2, ", from the shank to the tail")
        for i, (x, r) in enumerate(points):
            if not r > 0.0:
                raise ValueError(
                    f"body.points[{i}] = [{x:g}, {r:g}]: r must be > 0 m (a body with a hole in its"
                    " profile is two bodies)"
                )
            if i and not x > points[i - 1][0]:
                raise ValueError(
                    f"body.points[{i}] = [{x:g}, {r:g}]: x must exceed the previous point's x ="
                    f" {points[i - 1][0]:g} m (allowed: x strictly increasing)"
                )

    @property
    def start(self) -> float:
        """Where the body leaves the cylinder (m from the tip)."""
        return self.points[0][0]

    def check(self, radius: float, nose_length: float, length: float) -> None:
        """Raise ValueError unless the points start on the shank behind the nose and end at the tail."""
        x0, r0 = self.points[0]
        if not abs(r0 - radius) <= SHANK_RTOL * radius:
            raise ValueError(
                f"body.points[0]: r = {r0:g} m must be the shank radius (allowed: diameter/2 ="
                f" {radius:g} m, within {SHANK_RTOL:g} of it)"
            )
        if not x0 >= nose_length * (1 - 1e-12):
            raise ValueError(
                f"body.points[0]: x = {x0:g} m lies on the nose (allowed: x >= the nose length, {nose_length:g} m)"
            )
        last = self.points[-1][0]
        if not abs(last - length) <= 1e-9 * length:
            raise ValueError(
                f"body.points[{len(self.points) - 1}]: x = {last:g} m must be the tail (allowed:"
                f" the projectile's length, {length:g} m)"
            )

    def curve(self, radius: float, length: float) -> NoseCurve:
        """The interpolating curve, its first radius set to the shank ``radius`` and its end to ``length`` (m)."""
        x = np.array([p[0] for p in self.points])
        r = np.array([p[1] for p in self.points])
        r[0], x[-1] = radius, length
        return NoseCurve(x, r)


class NoseCurve:
    """The shape-preserving cubic Hermite interpolant ``r(s)`` through a nose's (or a body's) points (module
    docstring).

    Parameters
    ----------
    x, r : ndarray
        Strictly increasing distances from the tip (m) and non-decreasing radii (m).
    """

    def __init__(self, x: np.ndarray, r: np.ndarray) -> None:
        from scipy.interpolate import PchipInterpolator  # imported where used (slow to import)

        self.x, self.r = x, r
        self._radius = PchipInterpolator(x, r, extrapolate=False)
        self._slope = self._radius.derivative()
        self.knot_slopes = self._slope(x)

    @property
    def length(self) -> float:
        """Where the curve ends (m from the tip): the nose's length, or the tail."""
        return float(self.x[-1])

    def radius(self, s: np.ndarray | float) -> np.ndarray:
        """``r(s)`` (m) for ``x[0] <= s <= length`` (clipped to it)."""
        return self._radius(np.clip(s, self.x[0], self.length))

    def slope(self, s: np.ndarray | float) -> np.ndarray:
        """``dr/ds`` for ``x[0] <= s <= length`` (clipped to it)."""
        return self._slope(np.clip(s, self.x[0], self.length))

    def solve(self, radius: float) -> float:
        """The distance from the tip (m) where the curve first exceeds ``radius`` (m), ``0 < radius < r(length)``."""
        from scipy import optimize

        k = int(np.searchsorted(self.r, radius, side="right"))  # first point above the radius
        lo, hi = float(self.x[k - 1]), float(self.x[k])
        if self.r[k - 1] == radius:
            return lo
        return optimize.brentq(lambda s: float(self.radius(s)) - radius, lo, hi, xtol=1e-15, rtol=1e-15)

    def bezier(
        self, start: float, drop: float = 0.0, end: float | None = None
    ) -> tuple[list[tuple[float, float]], list[float], list[int]]:
        """The curve from ``start`` to ``end`` (default: its end, the shoulder of a nose), lowered by ``drop`` (m),
        as one cubic B-spline.

        Returns
        -------
        poles : list of (s, r)
            Control points: each piece's Bezier polygon, ``3 n + 1`` for ``n`` pieces.
        knots, multiplicities : lists
            Knot values (the pieces' ends, in m from the tip) and their multiplicities (4 at
            the ends, 3 inside: each piece is its own Bezier curve, joined with the interpolant's
            own continuity).
        """
        tol = 1e-9 * self.length
        end = self.length if end is None else end
        ends = [start] + [float(v) for v in self.x if start + tol < v < end - tol] + [end]
        poles = [(start, float(self.radius(start)) - drop)]
        for u, v in zip(ends[:-1], ends[1:]):
            h = v - u
            ru, rv = float(self.radius(u)), float(self.radius(v))
            du, dv = float(self.slope(u)), float(self.slope(v))
            poles += [(u + h / 3, ru + h * du / 3 - drop), (v - h / 3, rv - h * dv / 3 - drop), (v, rv - drop)]
        multiplicities = [4] + [3] * (len(ends) - 2) + [4]
        return poles, ends, multiplicities
