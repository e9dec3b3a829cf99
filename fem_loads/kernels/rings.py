"""The DAFL load of a body of revolution moving in a plane through its axis, integrated ring by ring.

A body of revolution is a stack of rings (:class:`RevolvedSurface`).  In a motion in the body's x-z plane
(velocity ``(v_x, 0, v_z)`` and pitch rate ``q``, body frame; the axis tilted by ``theta`` about the world Y
axis) everything the law needs is linear in ``c = cos phi`` around the ring at ``x`` of radius ``rho``:

* the normal velocity ``Vn = a + b c``, ``a = n_axial v_x``, ``b = n_radial v_z + q (rho n_axial - x n_radial)``;
* the height ``H = h0 + h1 c`` above the target surface, ``h0 = Z - x sin theta``, ``h1 = rho cos theta``.

So each switch of the load (separation, the ends of the contact and entry ramps, the friction cap) is one value
of ``c``.  Between consecutive switches the stress of the law ``c0 + c2 Vn^2``, wholly inside and at the full
law, has closed-form integrals in ``acos c`` and ``sqrt(1 - c^2)``; every other arc is smooth and Gauss-Legendre
in ``phi`` integrates it.  The stress is the points' pipeline (:func:`~fem_loads.factors.point_stress_scalars`)
with the law, switches and friction of :mod:`fem_loads.dafl`, on the exact surface instead of a mesh; the
body's mirror symmetry in the plane of motion halves each ring.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np
from numba import njit

from mesh import Profile

from ..dafl import DAFLLoads
from ..factors import Switches, contact_width_scalars, law_velocity_scalars, speed_scale_scalars
from ..resistance import ResistanceLaw
from ..target import LEVEL
from ..user_law import UserLaw
from .native import entry_factor, friction_stress, law_stress, point_stress, slip, slip_factor, switches
from .records import pack_effects, pack_laws

__all__ = [
    "RevolvedSurface",
    "revolved_surface",
    "ring_data",
    "pitch_plane_load",
    "lowest_height",
    "PitchPlaneLoad",
]

_RAMP_X, _RAMP_W = np.polynomial.legendre.leggauss(4)  # arcs of a ramp: the integrand is a smooth polynomial
_FRICTION_X, _FRICTION_W = np.polynomial.legendre.leggauss(6)  # arcs with friction: its slip direction too
OUTLINE_POINTS = 257  # samples of the profile where the lowest point is sought: 4 mm apart on a 1 m body
_PANEL = 0.25 * math.pi  # the longest arc one Gauss-Legendre rule covers (rad)


@dataclass(frozen=True)
class RevolvedSurface:
    """The rings of a body of revolution about its centre of mass.

    Attributes
    ----------
    rings : ndarray, shape (n, 5)
        Per ring: ``x`` (m, forward of the centre of mass), ``rho`` (m), ``n_axial``, ``n_radial``
        (the outward unit normal's components along the axis and outward from it) and ``w`` (m^2
        per radian: the ring's area is ``2 pi w``).
    outline : ndarray, shape (m, 2)
        ``(x, rho)`` along the profile from the tip to the tail's edge (its corners exactly): where the
        body's lowest point is sought (:func:`lowest_height`).
    """

    rings: np.ndarray
    outline: np.ndarray

    @property
    def area(self) -> float:
        """Total area (m^2)."""
        return float(2.0 * math.pi * self.rings[:, 4].sum())

    @property
    def max_radius(self) -> float:
        """Largest distance of a surface point from the centre of mass (m)."""
        return float(np.hypot(self.rings[:, 0], self.rings[:, 1]).max())

    def enclosed_volume(self) -> float:
        """``integral (r . n) dS / 3`` (m^3): the volume the surface encloses."""
        x, rho, n_axial, n_radial, w = self.rings.T
        return float(2.0 * math.pi * np.sum((x * n_axial + rho * n_radial) * w) / 3.0)


def revolved_surface(
    profile: Profile, tip_from_centre: float, nose_rings: int = 12, shank_rings: int = 8, face_rings: int = 4
) -> RevolvedSurface:
    """Rings at Gauss-Legendre stations of each smooth piece of ``profile``, and of its flat faces.

    Parameters
    ----------
    profile : Profile
        The outer profile (any analytic or measured nose).
    tip_from_centre : float
        Distance from the centre of mass forward to the nose tip (m).
    nose_rings : int
        Stations along the nose (shared among a measured nose's pieces, at least 4 each).
    shank_rings, face_rings : int
        Stations along the shank, and across the tail (and a blunt nose's flat tip) in radius.
    """
    length, nose = profile.length, profile.nose_length
    pieces = [0.0, *[b for b in profile.breakpoints if 0.0 < b < length], length]
    nose_pieces = max(1, sum(1 for a in pieces[:-1] if a < nose - 1e-12))
    rows = []
    for start, end in zip(pieces[:-1], pieces[1:]):
        count = shank_rings if start >= nose - 1e-12 else max(4, nose_rings // nose_pieces)
        nodes, weights = np.polynomial.legendre.leggauss(count)
        s = start + (end - start) * (nodes + 1.0) / 2.0  # distance from the tip
        ds = (end - start) / 2.0 * weights
        radius, slope = profile.radius_at(s), profile.slope_at(s)
        n_axial, n_radial = profile.outward_normal(s)
        rows.append(
            np.stack([tip_from_centre - s, radius, n_axial, n_radial, radius * np.sqrt(1.0 + slope**2) * ds], axis=1)
        )
    for x, face_normal, outer in (
        (tip_from_centre - length, -1.0, profile.tail_radius),
        (tip_from_centre, 1.0, profile.tip_radius),
    ):
        if outer > 0.0:  # a flat face: rings of radius rho, area rho d rho d phi
            nodes, weights = np.polynomial.legendre.leggauss(face_rings)
            rho, ones = outer * (nodes + 1.0) / 2.0, np.ones(face_rings)
            rows.append(np.stack([x * ones, rho, face_normal * ones, 0.0 * ones, rho * outer / 2.0 * weights], axis=1))
    s = np.unique(np.concatenate([np.linspace(0.0, length, OUTLINE_POINTS), pieces]))
    outline = np.stack([tip_from_centre - s, profile.radius_at(s)], axis=1)
    outline = np.vstack([[tip_from_centre, 0.0], outline])  # the tip's centre (a blunt nose's face)
    return RevolvedSurface(np.ascontiguousarray(np.concatenate(rows)), np.ascontiguousarray(outline))


def ring_data(loads: DAFLLoads, surface: RevolvedSurface) -> tuple[np.ndarray, np.ndarray]:
    """The law and effects records (:mod:`fem_loads.kernels.records`) of a mesh load's own law and effects, with
    the rings' radius and one entry length for every ring: the mesh's at its median point (``entry_smoothing`` times
    the square root of its weight).  Refuses what the rings do not integrate: a strength table, layers, a free
    surface, contact without separation, and a face that is not level."""
    law = loads.law
    if isinstance(law, ResistanceLaw) and law.strength_table:
        raise ValueError("the ring model takes no strength table")
    if not isinstance(law, ResistanceLaw | UserLaw):
        raise ValueError("the ring model takes one law, not layers")
    if loads.free_surface is not None or not loads.separation:
        raise ValueError("the ring model takes neither a free surface nor contact without separation")
    if loads.front_face != LEVEL:
        raise ValueError("the ring model takes a level target face")
    entry_length = loads.entry_smoothing * math.sqrt(float(np.median(loads.quadrature.weights)))
    laws, _, _, address = pack_laws(law)
    return laws, pack_effects(loads, loads.effect_values(entry_length, surface.max_radius), address)


_NO_TABLE = np.zeros(0)
#: ``(height, sin theta, cos theta, v_x, v_z, q)`` (:func:`pitch_plane_load`)
PlaneState = tuple[float, float, float, float, float, float]


@njit(cache=True, inline="always", error_model="numpy")
def _ring_stress(law: Any, effects: Any, switches: Switches, normal_velocity: float, height: float) -> float:
    """A ring point's stress (Pa) at ``Vn`` (m/s) and ``height`` (m above the surface): the law at ``max(Vn, 0)``
    and depth ``-height`` through the points' pipeline."""
    entry = effects.entry_length
    stress = law_stress(
        law, effects.user_law, law_velocity_scalars(normal_velocity, True), -height, _NO_TABLE, _NO_TABLE
    )
    return point_stress(stress, normal_velocity, -height, height, 1.0 / entry if entry > 0.0 else 0.0, switches)


@njit(cache=True, inline="always")
def _add_break(breaks: np.ndarray, count: int, value: float) -> int:
    if -1.0 < value < 1.0:
        breaks[count] = value
        count += 1
    return count


@njit(cache=True, inline="always")
def _breaks(
    breaks: np.ndarray,
    a: float,
    b: float,
    h0: float,
    h1: float,
    start: float,
    full: float,
    entry: float,
    cap_speed: float,
) -> int:
    """The values of ``c = cos phi`` where the load switches around one ring, with -1 and 1, sorted: ``Vn`` at the
    contact ramp's ``start`` and ``full`` and where friction reaches its cap (m/s), ``H`` at the ends of the entry
    ramp of length ``entry`` (m)."""
    breaks[0] = -1.0
    count = 1
    if b != 0.0:
        count = _add_break(breaks, count, (start - a) / b)
        count = _add_break(breaks, count, (full - a) / b)
        if cap_speed < math.inf:
            count = _add_break(breaks, count, (cap_speed - a) / b)
    if h1 != 0.0:
        count = _add_break(breaks, count, (-0.5 * entry - h0) / h1)  # wholly inside below this height
        if entry > 0.0:
            count = _add_break(breaks, count, (0.5 * entry - h0) / h1)  # nothing above this one
    breaks[count] = 1.0
    for i in range(2, count):  # insertion sort: at most five values between -1 and 1
        value, j = breaks[i], i - 1
        while breaks[j] > value:
            breaks[j + 1] = breaks[j]
            j -= 1
        breaks[j + 1] = value
    return count + 1


@njit(cache=True, inline="always")
def _closed_arc(low: float, high: float, a: float, b: float, static: float, dynamic: float) -> tuple[float, float]:
    """Integrals of ``sigma`` and ``sigma cos phi`` over the arc ``low < cos phi < high`` at the full law."""
    s_low = math.sqrt(max(1.0 - low * low, 0.0))
    s_high = math.sqrt(max(1.0 - high * high, 0.0))
    i0 = math.acos(low) - math.acos(high)  # integrals of cos^k phi, k = 0..3
    i1 = s_low - s_high
    i2 = 0.5 * (i0 + s_low * low - s_high * high)
    i3 = i1 - (s_low * s_low * s_low - s_high * s_high * s_high) / 3.0
    return (
        static * i0 + dynamic * (a * a * i0 + 2.0 * a * b * i1 + b * b * i2),
        static * i1 + dynamic * (a * a * i1 + 2.0 * a * b * i2 + b * b * i3),
    )


@njit(cache=True, inline="always")
def _gauss_arc(
    low: float,
    high: float,
    ring: tuple[float, float, float, float],
    motion: tuple[float, float, float, float, float, float, float],
    law: Any,
    effects: Any,
    switches: Switches,
    width: float,
) -> tuple[float, float, float, float, float]:
    """Integrals over the arc ``low < cos phi < high`` of the ``ring`` ``(x, rho, n_axial, n_radial)`` in the
    ``motion`` ``(a, b, h0, h1, v_x, v_z, q)``, by Gauss-Legendre panels of at most 45 degrees (6 points integrate
    cos^4 over one to 1e-9): ``sigma``, ``sigma cos phi``, and the friction stress's x and z components and its
    moment arm."""
    x, rho, n_axial, n_radial = ring
    a, b, h0, h1, vx, vz, q = motion
    entry, mu, cap = effects.entry_length, effects.friction, effects.friction_cap
    inverse_entry = 1.0 / entry if entry > 0.0 else 0.0
    j0 = j1 = jx = jz = jm = 0.0
    phi_low, phi_high = math.acos(high), math.acos(low)
    panels = int(math.ceil((phi_high - phi_low) / _PANEL))
    half = 0.5 * (phi_high - phi_low) / panels
    nodes, weights = (_FRICTION_X, _FRICTION_W) if mu > 0.0 else (_RAMP_X, _RAMP_W)
    for g in range(panels * nodes.shape[0]):
        phi = phi_low + (2 * (g // nodes.shape[0]) + 1) * half + half * nodes[g % nodes.shape[0]]
        c = math.cos(phi)
        vn = a + b * c
        height = h0 + h1 * c
        if entry_factor(height, entry > 0.0, inverse_entry) == 0.0:
            continue
        sigma = _ring_stress(law, effects, switches, vn, height)
        if sigma == 0.0:
            continue
        weight = half * weights[g % nodes.shape[0]]
        j0 += sigma * weight
        j1 += sigma * c * weight
        if mu > 0.0:
            tau = friction_stress(sigma, mu, cap)
            # the point (x, rho sin phi, rho cos phi) with normal (n_axial, n_radial sin phi, n_radial cos phi)
            s = math.sin(phi)
            sx, sy, sz = slip(
                (vx, 0.0, vz), (0.0, q, 0.0), (x, rho * s, rho * c), (n_axial, n_radial * s, n_radial * c), vn
            )
            k = slip_factor(sx * sx + sy * sy + sz * sz, width, vx * vx + vz * vz)
            jx += tau * k * sx * weight
            jz += tau * k * sz * weight
            jm += tau * k * (rho * c * sx - x * sz) * weight
    return j0, j1, jx, jz, jm


@njit(cache=True, inline="always")
def _uniform_ring(
    a: float,
    h0: float,
    vx: float,
    n_axial: float,
    n_radial: float,
    law: Any,
    effects: Any,
    switches: Switches,
    width: float,
) -> tuple[float, float]:
    """A ring loaded the same all round (``b = 0``, ``h1 = 0``: axial motion, the axis vertical): ``sigma`` over
    the half ring, and the friction's axial part (the slip along the meridian); no side load, exactly."""
    mu, cap = effects.friction, effects.friction_cap
    sigma = _ring_stress(law, effects, switches, a, h0)
    if sigma == 0.0:
        return 0.0, 0.0
    jx = 0.0
    if mu > 0.0:
        tau = friction_stress(sigma, mu, cap)
        sx = vx - a * n_axial
        jx = math.pi * tau * slip_factor(sx * sx + (a * n_radial) ** 2, width, vx * vx) * sx
    return math.pi * sigma, jx


@njit(cache=True)
def pitch_plane_load(
    rings: np.ndarray, laws: np.ndarray, effects_record: np.ndarray, state: PlaneState, out: np.ndarray
) -> None:
    """Force ``(F_x, F_z)`` (body frame, N) and pitch moment ``M_y`` (N m, about the centre of mass) into ``out``, in
    the ``state`` ``(height, sin theta, cos theta, v_x, v_z, q)``: the centre of mass's height above the target
    surface (m), the body's rotation ``theta`` about the world Y axis (body x in the world: ``(cos, -sin)`` in X, Z),
    the velocity in the body frame (m/s) and the pitch rate (rad/s)."""
    height, sin_theta, cos_theta, vx, vz, q = state
    law, effects = laws[0], effects_record[0]
    static, dynamic = law.c0, law.c2
    entry, mu, cap = effects.entry_length, effects.friction, effects.friction_cap
    speed_scale = speed_scale_scalars(math.sqrt(vx * vx + vz * vz), abs(q), effects.max_radius)
    width = contact_width_scalars(effects.contact_width, effects.contact_incidence, speed_scale)
    # the contact ramp runs from Vn = start to Vn = full (0 and W one-sided, -W/2 and W/2 centred)
    start, full = -effects.contact_offset * width, (1.0 - effects.contact_offset) * width
    # the law exactly c0 + c2 Vn^2: the closed forms below are its integrals (else Gauss-Legendre throughout)
    quadratic = effects.user_law == 0 and law.c1 == 0.0 and law.c == 0.0 and law.k == 0.0
    cap_speed = math.inf  # no cap
    if quadratic and mu > 0.0 and cap > mu * static and dynamic > 0.0:
        cap_speed = math.sqrt((cap / mu - static) / dynamic)
    ring_switches = switches(effects, width, 0.0, True, False, False)
    fx = fz = my = 0.0
    breaks = np.empty(8)
    for i in range(rings.shape[0]):
        x, rho, n_axial, n_radial, w = rings[i, 0], rings[i, 1], rings[i, 2], rings[i, 3], rings[i, 4]
        a = n_axial * vx
        b = n_radial * vz + q * (rho * n_axial - x * n_radial)
        h0 = height - sin_theta * x
        h1 = cos_theta * rho
        if h0 - abs(h1) >= 0.5 * entry or a + abs(b) <= start:
            continue  # wholly out of the target, or wholly moving away from it
        j0 = j1 = jx = jz = jm = 0.0
        if quadratic and mu == 0.0 and a - abs(b) >= full and h0 + abs(h1) <= -0.5 * entry:
            # wholly pressing at the full law and wholly inside: I0 = pi, I1 = 0, I2 = pi/2, I3 = 0
            j0 = math.pi * (static + dynamic * (a * a + 0.5 * b * b))
            j1 = math.pi * dynamic * a * b
        elif b == 0.0 and h1 == 0.0 and (mu == 0.0 or q == 0.0):
            j0, jx = _uniform_ring(a, h0, vx, n_axial, n_radial, law, effects, ring_switches, width)
        else:
            count = _breaks(breaks, a, b, h0, h1, start, full, entry, cap_speed)
            for m in range(count - 1):
                low, high = breaks[m], breaks[m + 1]
                middle = 0.5 * (low + high)
                speed_middle, height_middle = a + b * middle, h0 + h1 * middle
                if high <= low or speed_middle <= start or height_middle >= 0.5 * entry:
                    continue  # the arc moves away from the target, or lies outside it
                if quadratic and mu == 0.0 and speed_middle >= full and height_middle <= -0.5 * entry:
                    d0, d1 = _closed_arc(low, high, a, b, static, dynamic)
                    j0 += d0
                    j1 += d1
                else:
                    ring, motion = (x, rho, n_axial, n_radial), (a, b, h0, h1, vx, vz, q)
                    d0, d1, dx, dz, dm = _gauss_arc(low, high, ring, motion, law, effects, ring_switches, width)
                    j0, j1, jx, jz, jm = j0 + d0, j1 + d1, jx + dx, jz + dz, jm + dm
        # both halves of the ring: dF = -(sigma n + tau t) w dphi, dM = r x dF
        fx -= 2.0 * w * (n_axial * j0 + jx)
        fz -= 2.0 * w * (n_radial * j1 + jz)
        my -= 2.0 * w * ((rho * n_axial - x * n_radial) * j1 + jm)
    out[0] = fx
    out[1] = fz
    out[2] = my


@njit(cache=True)
def lowest_height(outline: np.ndarray, height: float, sin_theta: float, cos_theta: float) -> float:
    """Height (m) of the body's lowest point on its ``outline`` (:attr:`RevolvedSurface.outline`; negative
    once any point is inside)."""
    lowest = math.inf
    for i in range(outline.shape[0]):
        value = height - sin_theta * outline[i, 0] - abs(cos_theta * outline[i, 1])
        if value < lowest:
            lowest = value
    return lowest


class PitchPlaneLoad:
    """:func:`pitch_plane_load` callable from Python, in the DAFL load's terms.

    Parameters
    ----------
    surface : RevolvedSurface
    law : tuple of ndarray
        The law and effects records of :func:`ring_data` (or of :mod:`fem_loads.kernels.records`).
    """

    def __init__(self, surface: RevolvedSurface, law: tuple[np.ndarray, np.ndarray]) -> None:
        self.surface, (self.laws, self.effects) = surface, law

    def __call__(
        self, height: float, theta: float, velocity_body: tuple[float, float], pitch_rate: float
    ) -> np.ndarray:
        """``(F_x, F_z, M_y)`` in the body frame (N, N m) at ``height`` (m), ``theta`` (rad), ``(v_x, v_z)`` (m/s)
        and ``pitch_rate`` (rad/s)."""
        out = np.empty(3)
        vx, vz = float(velocity_body[0]), float(velocity_body[1])
        state = (float(height), math.sin(theta), math.cos(theta), vx, vz, float(pitch_rate))
        pitch_plane_load(self.surface.rings, self.laws, self.effects, state, out)
        return out
