"""Analytic axisymmetric projectile profiles and their exact 1-D integrals.

Every function here works in the *profile coordinates* of a projectile:
``s`` is the distance from the nose tip along the axis (m, ``0 <= s <= length``)
and ``r(s)`` is the outer radius (m).  The body frame used by the mesh and the
loads has its x axis along the projectile axis pointing *forward* (towards the
nose), so a point at distance ``s`` from the tip has ``x = -s`` before the
origin is moved to the centre of mass.

The 1-D integrals are the independent truth against which the finite-element
mass properties and surface quadrature are tested.
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from .measured import NoseCurve, ProfileBody, ProfileNose
from .moments import RevolvedMoments, revolved_moments

__all__ = [
    "OgiveNose",
    "ConeNose",
    "SecantOgiveNose",
    "BluntOgiveNose",
    "ProfileNose",
    "ProfileBody",
    "Profile",
    "Interior",
    "ProjectileGeometry",
    "RevolvedMoments",
    "revolved_moments",
]


@dataclass(frozen=True)
class OgiveNose:
    """Tangent ogive nose.

    Parameters
    ----------
    crh : float
        Caliber-radius-head: the ogive radius in projectile diameters (>= 0.5;
        0.5 is a hemisphere).
    """

    crh: float

    def __post_init__(self) -> None:
        if not (self.crh >= 0.5 and math.isfinite(self.crh)):
            raise ValueError(f"nose.crh = {self.crh}: must be a finite number >= 0.5")


@dataclass(frozen=True)
class ConeNose:
    """Conical nose.

    Parameters
    ----------
    half_angle : float
        Cone half-angle in degrees, 0 < half_angle < 90.
    """

    half_angle: float

    def __post_init__(self) -> None:
        if not (0.0 < self.half_angle < 90.0):
            raise ValueError(f"nose.half_angle = {self.half_angle}: must lie in (0, 90) degrees")


@dataclass(frozen=True)
class SecantOgiveNose:
    """Secant ogive: a circle arc of radius ``crh`` diameters through the tip and the shoulder.

    Parameters
    ----------
    crh : float
        Ogive radius in diameters; at least the tangent ogive's for this length
        (equality gives the tangent ogive).
    length : float
        Nose length in diameters.
    """

    crh: float
    length: float


@dataclass(frozen=True)
class BluntOgiveNose:
    """Flat-tipped (truncated) tangent ogive: the ogive of ``crh`` cut by a flat face.

    Parameters
    ----------
    crh : float
        Ogive radius in diameters (>= 0.5).
    flat_radius : float
        Radius (m) of the flat front face, smaller than the shank radius.
    """

    crh: float
    flat_radius: float


Nose = OgiveNose | ConeNose | SecantOgiveNose | BluntOgiveNose | ProfileNose


@dataclass(frozen=True)
class Profile:
    """Outer profile: a nose, a cylindrical shank (or a measured body: a boat tail, a flare) and a flat tail.

    Parameters
    ----------
    diameter : float
        Shank diameter (m).
    length : float
        Overall length from nose tip to tail (m); must exceed the nose length.
    nose : OgiveNose, ConeNose, SecantOgiveNose, BluntOgiveNose or ProfileNose
        Nose shape.  Every nose but the cone and the measured profile is a circle arc
        (:meth:`arc`); a measured profile is a cubic through its points (:attr:`curve`).
    body : ProfileBody, optional
        Where the body leaves the shank's cylinder and how it runs to the tail (measured points;
        :attr:`body_curve`); the tail is then a flat disc of radius :attr:`tail_radius`.
    """

    diameter: float
    length: float
    nose: Nose
    body: ProfileBody | None = None

    def __post_init__(self) -> None:
        if not (self.diameter > 0 and math.isfinite(self.diameter)):
            raise ValueError(f"diameter = {self.diameter}: must be a finite number > 0")
        a = self.radius
        if isinstance(self.nose, SecantOgiveNose):
            ln = self.nose.length * self.diameter
            tangent = (ln**2 + a**2) / (2 * a) / self.diameter
            if not (self.nose.length > 0 and math.isfinite(self.nose.length)):
                raise ValueError(f"nose.length = {self.nose.length}: must be a finite number > 0 (calibres)")
            if not (self.nose.crh >= tangent * (1 - 1e-12) and math.isfinite(self.nose.crh)):
                raise ValueError(
                    f"nose.crh = {self.nose.crh}: a secant ogive of length {self.nose.length} calibres"
                    f" needs crh >= {tangent:.6g} (the tangent ogive's)"
                )
        if isinstance(self.nose, BluntOgiveNose):
            if not (self.nose.crh >= 0.5 and math.isfinite(self.nose.crh)):
                raise ValueError(f"nose.crh = {self.nose.crh}: must be a finite number >= 0.5")
            if not (0.0 < self.nose.flat_radius < a):
                raise ValueError(f"nose.flat_radius = {self.nose.flat_radius}: must lie in (0, {a:.6g}) m")
        if isinstance(self.nose, ProfileNose):
            self.nose.check_shank(a)
        if not (self.length > self.nose_length and math.isfinite(self.length)):
            raise ValueError(f"length = {self.length}: must exceed the nose length {self.nose_length:.6g} m")
        if self.body is not None:
            self.body.check(a, self.nose_length, self.length)

    @property
    def radius(self) -> float:
        """Shank radius ``a`` (m)."""
        return 0.5 * self.diameter

    @property
    def ogive_radius(self) -> float:
        """Ogive radius ``R = crh * diameter`` (m); only for ogive noses."""
        nose = self.nose
        if isinstance(nose, (ConeNose, ProfileNose)):  # no ``crh``: the AttributeError reading it would raise
            raise AttributeError(f"ogive_radius: a {type(nose).__name__} has no ogive radius")
        return nose.crh * self.diameter

    @functools.cached_property
    def curve(self) -> NoseCurve | None:
        """The interpolating curve of a measured nose (:mod:`mesh.measured`), or None."""
        return self.nose.curve(self.radius) if isinstance(self.nose, ProfileNose) else None

    @functools.cached_property
    def body_curve(self) -> NoseCurve | None:
        """The interpolating curve of a measured body, from where it leaves the cylinder to the tail, or None."""
        return self.body.curve(self.radius, self.length) if self.body is not None else None

    @property
    def tail_radius(self) -> float:
        """Radius (m) of the flat tail disc: the shank's, or a measured body's last."""
        return float(self.body_curve.r[-1]) if self.body_curve is not None else self.radius

    @property
    def largest_radius(self) -> float:
        """The profile's largest radius (m): the shank's, or a flare's (the cubic never overshoots its points)."""
        return max(self.radius, float(self.body_curve.r.max())) if self.body_curve is not None else self.radius

    @property
    def breakpoints(self) -> tuple[float, ...]:
        """Distances from the tip (m) where the profile's curvature jumps: the shoulder, a measured nose's points,
        and a measured body's points before the tail."""
        nose = tuple(float(x) for x in self.curve.x[1:]) if self.curve is not None else (self.nose_length,)
        if self.body_curve is None:
            return nose
        return nose + tuple(float(x) for x in self.body_curve.x[:-1] if x > self.nose_length)

    def arc(self) -> tuple[float, float, float] | None:
        """``(s_c, r_c, R)``: centre and radius of the nose arc in profile coordinates, or None (cone, measured).

        The nose is ``r(s) = r_c + sqrt(R^2 - (s - s_c)^2)`` for ``0 <= s <= nose_length``.
        """
        a, d = self.radius, self.diameter
        nose = self.nose
        if isinstance(nose, (ConeNose, ProfileNose)):
            return None
        if isinstance(nose, SecantOgiveNose):
            big_r, ln = nose.crh * d, nose.length * d
            chord = math.hypot(ln, a)
            h = math.sqrt(max(big_r**2 - 0.25 * chord**2, 0.0))
            return 0.5 * ln + h * a / chord, 0.5 * a - h * ln / chord, big_r
        big_r = nose.crh * d
        full = math.sqrt(big_r**2 - (big_r - a) ** 2)  # the tangent ogive's length
        if isinstance(nose, BluntOgiveNose):
            cut = full - math.sqrt(big_r**2 - (nose.flat_radius + big_r - a) ** 2)
            return full - cut, a - big_r, big_r
        return full, a - big_r, big_r

    @property
    def tip_radius(self) -> float:
        """Radius (m) of the flat front face (zero for pointed noses)."""
        return self.nose.flat_radius if isinstance(self.nose, BluntOgiveNose) else 0.0

    @property
    def nose_length(self) -> float:
        """Axial length of the nose (m)."""
        nose = self.nose
        if isinstance(nose, ConeNose):
            return self.radius / math.tan(math.radians(nose.half_angle))
        if isinstance(nose, SecantOgiveNose):
            return nose.length * self.diameter
        if isinstance(nose, ProfileNose):
            return nose.length
        arc = self.arc()  # a tangent ogive meets the shank at the top of its arc
        assert arc is not None  # every nose without an arc returned above
        return arc[0]

    def radius_at(self, s: np.ndarray | float) -> np.ndarray:
        """Outer radius ``r(s)`` (m) at distance ``s`` from the tip (m)."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        a, ln = self.radius, self.nose_length
        arc = self.arc()
        nose: np.ndarray | float
        if self.curve is not None:
            nose = self.curve.radius(s)
        elif arc is None:
            assert isinstance(self.nose, ConeNose)  # no arc and no curve: a cone
            nose = s * math.tan(math.radians(self.nose.half_angle))
        else:
            s_c, r_c, big_r = arc
            nose = r_c + np.sqrt(np.maximum(big_r**2 - (s - s_c) ** 2, 0.0))
        body = self.body_curve.radius if self.body_curve is not None else None
        return np.where(s < ln, np.maximum(nose, 0.0), self._body(s, a, body))

    def _body(
        self, s: np.ndarray | float, shank: float, of_body: Callable[[np.ndarray | float], np.ndarray] | None
    ) -> np.ndarray | float:
        """Behind the nose: ``shank`` on the cylinder, ``of_body(s)`` on a measured body."""
        if of_body is None or self.body is None:  # the body's curve (``of_body``) exists with the body only
            return shank
        return np.where(s < self.body.start, shank, of_body(s))

    def slope_at(self, s: np.ndarray | float) -> np.ndarray:
        """``dr/ds`` of the outer profile (zero on the shank)."""
        s = np.clip(np.asarray(s, dtype=float), 0.0, self.length)
        ln = self.nose_length
        arc = self.arc()
        nose: np.ndarray | float
        if self.curve is not None:
            nose = self.curve.slope(s)
        elif arc is None:
            assert isinstance(self.nose, ConeNose)  # no arc and no curve: a cone
            nose = np.full_like(s, math.tan(math.radians(self.nose.half_angle)))
        else:
            s_c, _, big_r = arc
            u = s_c - s
            nose = u / np.sqrt(np.maximum(big_r**2 - u**2, 1e-300))
        body = self.body_curve.slope if self.body_curve is not None else None
        return np.where(s < ln, nose, self._body(s, 0.0, body))

    def outward_normal(self, s: np.ndarray | float) -> tuple[np.ndarray, np.ndarray]:
        """Exact outward normal of the lateral surface at ``s``.

        Returns
        -------
        n_forward, n_radial : ndarray
            Components along the forward axis (``+x``, towards the tip) and
            along the outward radial direction.  ``n_forward = sin(slope angle)``
            is positive on the nose and zero on the shank.
        """
        slope = self.slope_at(s)
        scale = 1.0 / np.sqrt(1.0 + slope**2)
        return slope * scale, scale

    def nose_factor(self) -> float:
        """Frictionless nose shape factor ``N`` of the cavity-expansion axial force.

        ``N = (8 psi - 1) / (24 psi^2)`` for a tangent ogive of CRH ``psi`` and
        ``sin^2(half-angle)`` for a cone (brief section 5); for the other noses
        ``N = [pi r_tip^2 + int 2 pi r r' sin^2(slope) ds] / (pi a^2)``, integrated
        to 1e-12.
        """
        if isinstance(self.nose, OgiveNose):
            psi = self.nose.crh
            return (8.0 * psi - 1.0) / (24.0 * psi**2)
        if isinstance(self.nose, ConeNose):
            return math.sin(math.radians(self.nose.half_angle)) ** 2

        def integrand(s: float) -> float:
            slope = float(self.slope_at(s))
            return 2 * math.pi * float(self.radius_at(s)) * slope**3 / (1 + slope**2)

        from scipy import integrate  # imported where used (slow to import)

        points = [p for p in self.breakpoints if p < self.nose_length] or None
        lateral = integrate.quad(
            integrand,
            0.0,
            self.nose_length,
            points=points,
            epsabs=0.0,
            epsrel=1e-12,
            limit=max(200, 4 * len(self.breakpoints)),
        )[0]
        return (math.pi * self.tip_radius**2 + lateral) / (math.pi * self.radius**2)

    def lateral_area(self, s0: float = 0.0, s1: float | None = None) -> float:
        """Area (m^2) of the lateral surface between ``s0`` and ``s1``."""
        s1 = self.length if s1 is None else s1
        from scipy import integrate

        points = [p for p in self.breakpoints if s0 < p < s1]
        value, _ = integrate.quad(
            lambda s: 2 * math.pi * float(self.radius_at(s)) * math.sqrt(1 + float(self.slope_at(s)) ** 2),
            s0,
            s1,
            points=points or None,
            epsabs=0.0,
            epsrel=1e-12,
            limit=max(200, 4 * len(points)),
        )
        return value

    def surface_area(self) -> float:
        """Total outer area (m^2): lateral surface, flat tail disc and flat front face."""
        return self.lateral_area() + math.pi * (self.tail_radius**2 + self.tip_radius**2)


@dataclass(frozen=True)
class Interior:
    """A hollow interior: a cavity a wall thickness inside the outer profile.

    The cavity radius is ``r(s) - wall_thickness`` (brief section 4) and the
    cavity ends ``tail_thickness`` before the tail.

    Parameters
    ----------
    wall_thickness : float
        Radial wall thickness (m), ``0 < wall_thickness < radius``.
    tail_thickness : float
        Thickness of the tail plate (m).
    """

    wall_thickness: float
    tail_thickness: float


@dataclass(frozen=True)
class ProjectileGeometry:
    """Geometry of a projectile: outer profile, optional cavity and counterweight.

    Parameters
    ----------
    profile : Profile
        Outer profile.
    interior : Interior or None
        Cavity; ``None`` for a solid projectile.
    counterweight : tuple of float or None
        ``(start, end)``: distances from the nose tip (m) of the two
        cross-sections between which the counterweight fills the cavity.
        The rest of the cavity is empty.
    """

    profile: Profile
    interior: Interior | None = None
    counterweight: tuple[float, float] | None = None

    def __post_init__(self) -> None:
        if self.interior is not None and self.profile.tip_radius > 0:
            raise ValueError("interior: a flat-tipped (blunt) nose with a cavity is not supported")
        if self.interior is None:
            if self.counterweight is not None:
                raise ValueError("counterweight: needs an interior (a cavity to fill)")
            return
        t, tail = self.interior.wall_thickness, self.interior.tail_thickness
        a = self.profile.radius
        if not (0.0 < t < a):
            raise ValueError(f"interior.wall_thickness = {t}: must lie in (0, {a:.6g}) m")
        lo, hi = self.cavity_start, self.profile.length
        if not (0.0 < tail < hi - lo):
            raise ValueError(f"interior.tail_thickness = {tail}: must lie in (0, {hi - lo:.6g}) m")
        body = self.profile.body
        if body is not None and body.start < self.cavity_end:
            # a boat tail narrows the body: the wall must leave a cavity all the way to its end
            s = np.linspace(body.start, self.cavity_end, 401)
            narrowest = float(self.profile.radius_at(s).min())
            if not t < narrowest:
                raise ValueError(
                    f"interior.wall_thickness = {t}: must be less than the body's narrowest radius"
                    f" before the tail plate, {narrowest:.6g} m (a thinner wall or a thicker tail plate)"
                )
        if self.counterweight is not None:
            x1, x2 = self.counterweight
            if not (self.cavity_start <= x1 < x2 <= self.cavity_end):
                raise ValueError(
                    f"counterweight = ({x1}, {x2}): need {self.cavity_start:.6g} <= start < end"
                    f" <= {self.cavity_end:.6g} m (the cavity)"
                )

    @property
    def cavity_start(self) -> float:
        """Distance from the tip (m) of the cavity apex, where ``r(s) = wall_thickness``."""
        if self.interior is None:
            raise ValueError("no interior")
        t = self.interior.wall_thickness
        p = self.profile
        if p.curve is not None:
            return p.curve.solve(t)
        arc = p.arc()
        if arc is not None:
            s_c, r_c, big_r = arc
            return s_c - math.sqrt(big_r**2 - (t - r_c) ** 2)
        assert isinstance(p.nose, ConeNose)  # no curve and no arc: a cone
        return t / math.tan(math.radians(p.nose.half_angle))

    @property
    def cavity_end(self) -> float:
        """Distance from the tip (m) of the cavity's flat end."""
        if self.interior is None:
            raise ValueError("no interior")
        return self.profile.length - self.interior.tail_thickness

    def cavity_radius_at(self, s: np.ndarray | float) -> np.ndarray:
        """Cavity radius (m) at ``s``; zero outside the cavity."""
        if self.interior is None:
            return np.zeros_like(np.asarray(s, dtype=float))
        s = np.asarray(s, dtype=float)
        inside = (s >= self.cavity_start) & (s <= self.cavity_end)
        return np.where(inside, np.maximum(self.profile.radius_at(s) - self.interior.wall_thickness, 0.0), 0.0)
