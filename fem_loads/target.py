"""Targets and optional load effects: the front face, layers, free-surface reduction, friction.

Every effect is optional, and :class:`~fem_loads.dafl.DAFLLoads` pays only for those a scene asks for.  Their
factors are those of :mod:`fem_loads.factors`; docs/effects.md gives the equations and their sources.

* **Front face**: the plane ``n . X = d`` (world frame) through which the body enters, the target on its far
  side.  A point ``r`` (body frame) of a body at ``X_c`` turned by ``R`` lies ``H = (n . X_c - d) + (R^T n) . r``
  above it (its depth is ``-H``): :func:`face_frame_scalars` gives the centre's height and ``R^T n``.
* **Layers**: interfaces at depths ``d_1 < d_2 < ...``; a point uses the law of the layer containing it, blended
  with the next layer's across each interface over the point's own extent ``l``.
* **Free-surface reduction**: the normal stress at depth ``d`` times ``f(d) = f0 + (1 - f0) S(d / D)``.
* **Friction**: a tangential stress opposite to the local slip ``u - Vn n``, ``tau = min(mu sigma_n, tau_s)``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from .factors import free_face_distance_scalars, friction_stress_scalars, layer_share_scalars, surface_factor_scalars
from .resistance import ResistanceLaw
from .user_law import UserLaw

__all__ = [
    "FrontFace",
    "LEVEL",
    "GAP",
    "face_height_scalars",
    "face_frame_scalars",
    "LayeredTarget",
    "FreeSurface",
    "Friction",
    "slip_factor_scalars",
]


@dataclass(frozen=True)
class FrontFace:
    """The target's front face, the plane ``normal . X = offset`` (world frame; ``offset`` in m): the target lies
    on the side the unit ``normal`` points away from."""

    normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
    offset: float = 0.0

    def __post_init__(self) -> None:
        normal = np.asarray(self.normal, dtype=float)
        if normal.shape != (3,) or not np.all(np.isfinite(normal)) or abs(float(normal @ normal) - 1.0) > 1e-12:
            raise ValueError(f"front face normal = {self.normal}: must be a unit vector of 3 finite numbers")
        if not math.isfinite(self.offset):
            raise ValueError(f"front face offset = {self.offset}: must be a finite number (m)")

    def behind(self, depth: float) -> FrontFace:
        """The plane ``depth`` (m) below this face, facing back out of the target: a point's height above it is
        its depth below this face less ``depth`` (``behind(0)``: the depth itself; ``behind(T)``: past a rear
        face at ``T``)."""
        return FrontFace((-self.normal[0], -self.normal[1], -self.normal[2]), depth - self.offset)


#: the level half-space Z < 0
LEVEL = FrontFace()
#: the law of a gap between layers, and of the empty space behind a target's rear face: no stress
GAP = ResistanceLaw(0.0, 0.0, "air")


def face_height_scalars(position: Any, normal: Any, offset: float) -> Any:
    """``n . X - d``: the height (m) of ``position`` (world frame) above the face ``normal . X = offset``."""
    return normal[0] * position[0] + normal[1] * position[1] + normal[2] * position[2] - offset


def face_frame_scalars(position: Any, rotation: Any, normal: Any, offset: float) -> tuple[Any, Any, Any, Any]:
    """``(h, u0, u1, u2)``: the height ``h`` (m) of the centre of mass ``position`` above the face
    ``normal . X = offset``, and ``u = R^T n``, the face's normal in the body frame (``rotation`` ``R``, body to
    world), so that a point ``r`` of the body lies ``h + u . r`` above the face."""
    n0, n1, n2 = normal[0], normal[1], normal[2]
    r0, r1, r2 = rotation[0], rotation[1], rotation[2]  # rows: nested lists work too (plain floats are fast)
    up0 = n0 * r0[0] + n1 * r1[0] + n2 * r2[0]
    up1 = n0 * r0[1] + n1 * r1[1] + n2 * r2[1]
    up2 = n0 * r0[2] + n1 * r1[2] + n2 * r2[2]
    return face_height_scalars(position, normal, offset), up0, up1, up2


@dataclass(frozen=True)
class LayeredTarget:
    """Layers parallel to the surface, from the top down.

    Parameters
    ----------
    thicknesses : sequence of float
        Thickness (m) of every layer but the last, which extends to infinity.
    laws : sequence of ResistanceLaw or UserLaw
        One law per layer (``len(thicknesses) + 1`` of them); :data:`GAP` for a gap, and as the last, the space
        behind a target of finite thickness.
    """

    thicknesses: tuple[float, ...]
    laws: tuple[ResistanceLaw | UserLaw, ...]
    #: every layered target depends on depth
    depth_dependent = True

    def __post_init__(self) -> None:
        if len(self.laws) != len(self.thicknesses) + 1:
            raise ValueError("layers: every layer but the last needs a thickness")
        if not all(t > 0 and math.isfinite(t) for t in self.thicknesses):
            raise ValueError("layers: thicknesses must be finite numbers > 0")

    @property
    def interfaces(self) -> np.ndarray:
        """The interfaces' depths (m below the surface), from the top down."""
        return np.cumsum(self.thicknesses)

    def normal_stress(
        self, normal_velocity: np.ndarray, depth: np.ndarray, lengths: np.ndarray | None = None
    ) -> np.ndarray:
        """The stress (Pa) at each point: its layer's law, blended with the next layer's across each interface.

        ``lengths`` (m, one per point, or None): the width over which each point's stress blends from one
        layer to the next, centred on the interface; zero or None is the sharp switch.  Each layer's law is
        evaluated only where it has a share.
        """
        stress = np.zeros(np.shape(normal_velocity))
        smooth = lengths is not None and bool(np.any(lengths))
        inverse = 1.0 / np.asarray(lengths) if smooth else 0.0
        bounds = [-math.inf, *self.interfaces, math.inf]
        for law, top, bottom in zip(self.laws, bounds[:-1], bounds[1:]):
            share = np.broadcast_to(layer_share_scalars(top, bottom, depth, smooth, inverse), stress.shape)
            where = share != 0.0
            if where.any():
                stress[where] += share[where] * law.normal_stress(normal_velocity[where], depth[where])
        return stress


@dataclass(frozen=True)
class FreeSurface:
    """Free-surface reduction of the normal stress near the surface.

    Parameters
    ----------
    depth : float
        Depth ``D`` (m) below which the full resistance acts.
    surface_fraction : float
        Fraction ``f0`` of the resistance at the surface itself, 0 <= f0 <= 1.
    front : bool
        The reduction applies near the front face (default).
    rear_face : float
        And near a rear face at this depth (m below the front face); ``inf`` (default): not.
    """

    depth: float
    surface_fraction: float = 0.0
    front: bool = True
    rear_face: float = math.inf

    def factor(self, depth: np.ndarray) -> np.ndarray:
        """``f0 + (1 - f0) S(d / D)`` (:func:`~fem_loads.factors.surface_factor_scalars`) at the distance ``d`` from
        the nearest free face it applies at, of points at ``depth`` (m): ``f0`` at the face, 1 from ``D`` in."""
        distance = free_face_distance_scalars(np.asarray(depth, dtype=float), self.front, self.rear_face)
        return np.asarray(surface_factor_scalars(distance, 1.0 / self.depth, self.surface_fraction))


@dataclass(frozen=True)
class Friction:
    """Tangential stress opposite to the slip: ``mu sigma_n``, capped at ``cap`` (Pa) if given."""

    coefficient: float
    cap: float | None = None

    def stress(self, sigma: np.ndarray) -> np.ndarray:
        """``mu sigma_n``, capped at ``cap`` (Pa) (:func:`~fem_loads.factors.friction_stress_scalars`)."""
        return np.asarray(friction_stress_scalars(sigma, self.coefficient, self.cap or 0.0))


def slip_scalars(
    v: tuple[float, float, float],
    w: tuple[float, float, float],
    r: tuple[float, float, float],
    m: tuple[float, float, float],
    normal_velocity: float,
) -> tuple[float, float, float]:
    """The slip ``s = u - Vn m`` (m/s, body frame) of a point ``r`` (m) with outward normal ``m``: its velocity
    ``u = v + w x r`` less the normal part, for the body's velocity ``v`` (m/s) and angular velocity ``w`` (rad/s).
    The compiled kernels' points and rings take it as it is; the numpy load sums its expansion over all the points
    (``|s|^2 = |u|^2 - Vn^2``, :meth:`~fem_loads.dafl.DAFLLoads.slip`)."""
    return (
        v[0] + w[1] * r[2] - w[2] * r[1] - normal_velocity * m[0],
        v[1] + w[2] * r[0] - w[0] * r[2] - normal_velocity * m[1],
        v[2] + w[0] * r[1] - w[1] * r[0] - normal_velocity * m[2],
    )


def slip_factor_scalars(slip2: Any, width: float, speed2: float) -> Any:
    """``k``, with which the friction stress along the slip ``s`` is ``tau k s``: ``1 / sqrt(|s|^2 + W^2)``
    with a contact width ``W > 0`` (continuous through zero slip); sharp, ``1/|s|`` where ``|s|^2 > 1e-24 |V|^2``
    and 0 elsewhere (the direction is undefined at zero slip).  ``slip2 = |s|^2`` (m^2/s^2)."""
    if width > 0.0:
        return 1.0 / np.sqrt(slip2 + width * width)
    moving = slip2 > 1e-24 * speed2
    return moving / np.sqrt(np.maximum(slip2, 1e-300))
