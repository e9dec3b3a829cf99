"""Moments of a solid of revolution (volume, first moment, axial and transverse second moments) from 1-D
integrals of its radius: the independent truth the mass properties are checked against."""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass

import numpy as np

__all__ = ["RevolvedMoments", "revolved_moments"]


@dataclass(frozen=True)
class RevolvedMoments:
    """Per-unit-density moments of a solid of revolution about the nose tip.

    Attributes
    ----------
    volume : float
        ``int pi r^2 ds`` (m^3).
    first_moment : float
        ``int pi r^2 s ds`` (m^4).
    axial_second_moment : float
        ``int pi r^4 / 2 ds`` (m^5): axial moment of inertia per unit density.
    transverse_second_moment : float
        ``int (pi r^4 / 4 + pi r^2 s^2) ds`` (m^5): transverse moment of
        inertia per unit density about an axis through the tip.
    """

    volume: float
    first_moment: float
    axial_second_moment: float
    transverse_second_moment: float

    def __add__(self, other: RevolvedMoments) -> RevolvedMoments:
        return RevolvedMoments(*(a + b for a, b in zip(self.astuple(), other.astuple())))

    def __sub__(self, other: RevolvedMoments) -> RevolvedMoments:
        return RevolvedMoments(*(a - b for a, b in zip(self.astuple(), other.astuple())))

    def __mul__(self, density: float) -> RevolvedMoments:
        return RevolvedMoments(*(density * a for a in self.astuple()))

    __rmul__ = __mul__

    def astuple(self) -> tuple[float, float, float, float]:
        return (self.volume, self.first_moment, self.axial_second_moment, self.transverse_second_moment)


def revolved_moments(
    radius: Callable[[np.ndarray | float], np.ndarray],
    s0: float,
    s1: float,
    breakpoints: Sequence[float] = (),
    cubic: bool = False,
) -> RevolvedMoments:
    """Moments of the solid of revolution of ``radius(s)`` for ``s0 <= s <= s1``.

    Parameters
    ----------
    radius : callable
        ``radius(s) -> r`` (m), for a float or (with ``cubic``) an array ``s`` (m).
    s0, s1 : float
        Axial limits (m from the tip).
    breakpoints : sequence of float
        Points where ``radius`` has a kink, passed to the quadrature.
    cubic : bool
        ``radius`` is a cubic polynomial between breakpoints (a measured nose): every integrand is then
        a polynomial of degree at most 12 there, integrated exactly by 7-point Gauss-Legendre on each piece.
    """
    if s1 <= s0:
        return RevolvedMoments(0.0, 0.0, 0.0, 0.0)
    if cubic:
        ends = np.array([s0, *sorted(p for p in breakpoints if s0 < p < s1), s1])
        nodes, weights = np.polynomial.legendre.leggauss(7)
        half = 0.5 * np.diff(ends)[:, None]
        s = (0.5 * (ends[:-1] + ends[1:]))[:, None] + half * nodes
        w = (half * weights).ravel()
        s = s.ravel()
        r2 = np.asarray(radius(s), dtype=float) ** 2
        return RevolvedMoments(
            *(math.pi * float(np.dot(w, f)) for f in (r2, r2 * s, 0.5 * r2**2, 0.25 * r2**2 + r2 * s * s))
        )
    from scipy import integrate

    points = [p for p in breakpoints if s0 < p < s1] or None
    limit = max(200, 4 * len(points or ()))
    integrands = (
        lambda s: math.pi * float(radius(s)) ** 2,
        lambda s: math.pi * float(radius(s)) ** 2 * s,
        lambda s: 0.5 * math.pi * float(radius(s)) ** 4,
        lambda s: 0.25 * math.pi * float(radius(s)) ** 4 + math.pi * float(radius(s)) ** 2 * s * s,
    )
    values = [integrate.quad(f, s0, s1, points=points, epsabs=0.0, epsrel=1e-13, limit=limit)[0] for f in integrands]
    return RevolvedMoments(*values)
