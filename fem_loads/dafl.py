"""Differential area force law (DAFL): resultant target loads on a rigid projectile.

A surface quadrature point with outward normal ``n`` at ``r`` from the centre of mass moves with
``u = V + omega x r``: its normal velocity is ``Vn = u . n`` (positive into the target), its normal stress
``sigma_n`` the pipeline of :mod:`fem_loads.factors` (the target's law times the contact, free-surface and entry
factors and the exposure), and the load ``F = -sum sigma_n n dS``, ``M = sum r x dF``.  The optional effects are
those of :mod:`fem_loads.target`; an absent one costs nothing.  docs/model.md explains the contact model and the
switches' widths.

A mirror-symmetric quadrature is evaluated as its images' rows and summed in mirrored pairs
(:mod:`fem_loads.images`); the friction load is summed over all points in their own order.
"""

from __future__ import annotations

import math
from types import SimpleNamespace
from typing import Any, NamedTuple

import numpy as np

from .factors import (
    contact_width_scalars,
    law_velocity_scalars,
    point_stress_scalars,
    speed_scale_scalars,
    switches_scalars,
)
from .images import MirrorImages
from .quadrature import SurfaceQuadrature
from .resistance import ResistanceLaw
from .target import (
    LEVEL,
    FreeSurface,
    Friction,
    FrontFace,
    LayeredTarget,
    face_frame_scalars,
    face_height_scalars,
    slip_factor_scalars,
)
from .user_law import UserLaw

__all__ = ["DAFLLoads", "SurfaceStress", "CONTACT_MODELS", "effect_values"]


class SurfaceStress(NamedTuple):
    """The stresses of the DAFL at every surface quadrature point, as the loads integrate them.

    Attributes
    ----------
    sigma_n : ndarray, shape (n,)
        Normal stress (Pa); 0 where a point is outside the target or separated.
    tau : ndarray, shape (n,) or None
        Magnitude of the tangential stress (Pa), acting against the local slip; None without friction.
    normal_velocity : ndarray, shape (n,)
        ``Vn`` (m/s), positive into the target.
    exposure : ndarray, shape (n,)
        The exposure factor (:mod:`fem_loads.exposure`): 1 where the target reaches the point, 0 where the body
        ahead hides it.
    """

    sigma_n: np.ndarray
    tau: np.ndarray | None
    normal_velocity: np.ndarray
    exposure: np.ndarray


CONTACT_MODELS = ("one_sided", "centred")


class DAFLLoads:
    """Resultant force and moment of the DAFL for a rigid-body velocity state.

    Parameters
    ----------
    quadrature : SurfaceQuadrature
        Outer-surface quadrature in the body frame about the centre of mass.
    law : ResistanceLaw, UserLaw or LayeredTarget
        Normal stress (Pa) as a function of the normal velocity and the depth.
    normal_velocity_guard : float
        Sharp contact only (``contact_width = contact_incidence = 0``): a point carries stress only when
        ``Vn > guard * (|V| + |omega| r_max)``, so that round-off in ``Vn`` on a shank sliding along its axis
        switches on no stress.
    friction : Friction, optional
        Tangential stress; none by default.
    separation : bool
        True (default): no stress where ``Vn <= 0`` (below the contact ramp).  False, for comparison: every
        embedded point stays in contact with ``max(0, f(Vn, z))``, and the loads can do positive work.
    free_surface : FreeSurface, optional
        Reduction of the normal stress near the surface; none by default.
    contact_width, contact_incidence : float
        ``w`` (m/s) and ``delta``: the contact width ``W = w + delta U`` (``U = |V| + |omega| r_max``, the
        speed scale) over which a point's stress rises from 0 to the full law, and with friction the slip
        speed below which the friction's direction fades.  ``w = delta = 0``: sharp.
    contact : {"one_sided", "centred"}
        The ramp: ``c = S(Vn / W)``, from 0 at ``Vn = 0`` to 1 at ``Vn = W``, or ``c = S(1/2 + Vn / W)``,
        centred on ``Vn = 0`` (docs/model.md); the law is evaluated at ``max(Vn, 0)`` in both.
    entry_smoothing : float
        The length ``l`` over which a point enters the target (and crosses a layer interface), in units of
        the square root of its quadrature weight.  0: sharp.
    exposure : bool
        True (default): a point the target cannot reach (:mod:`fem_loads.exposure`) carries no stress.  A
        quadrature without an exposure table (a convex body) is unaffected.
    front_face : FrontFace
        The plane through which the body enters the target; the level face ``Z = 0`` by default.
    """

    def __init__(
        self,
        quadrature: SurfaceQuadrature,
        law: ResistanceLaw | UserLaw | LayeredTarget,
        normal_velocity_guard: float = 1e-9,
        *,
        friction: Friction | None = None,
        separation: bool = True,
        free_surface: FreeSurface | None = None,
        contact_width: float = 0.0,
        contact_incidence: float = 0.0,
        contact: str = "one_sided",
        entry_smoothing: float = 0.0,
        exposure: bool = True,
        front_face: FrontFace = LEVEL,
    ) -> None:
        if not (contact_width >= 0.0 and contact_incidence >= 0.0 and entry_smoothing >= 0.0):
            raise ValueError("contact_width, contact_incidence and entry_smoothing must be >= 0")
        if contact not in CONTACT_MODELS:
            raise ValueError(f"contact = {contact!r}: must be one of {', '.join(CONTACT_MODELS)}")
        self.quadrature, self.law = quadrature, law
        self.normal_velocity_guard = float(normal_velocity_guard)
        self.friction, self.separation, self.free_surface = friction, separation, free_surface
        self.contact_width, self.entry_smoothing = float(contact_width), float(entry_smoothing)
        self.contact_incidence, self.contact = float(contact_incidence), contact
        self.front_face = front_face
        q = quadrature
        # [n | r x n]: one product gives Vn = n.V + (r x n).omega, and the weighted stresses times
        # it give force and moment together; stored transposed, (6, n), for row-combining products
        self._normal_arm = np.ascontiguousarray(np.hstack([q.normals, q.moment_arms]))
        self._normal_arm_t = np.ascontiguousarray(self._normal_arm.T)
        self._points = np.ascontiguousarray(q.points)
        self._points_t = np.ascontiguousarray(q.points.T)
        self._normals = np.ascontiguousarray(q.normals)
        self._weights = np.ascontiguousarray(q.weights)
        self._radius2 = np.einsum("ij,ij->i", q.points, q.points)
        #: ``r_max`` (m): the farthest point's distance from the centre of mass (the bounding sphere)
        self.max_radius = float(np.sqrt(self._radius2.max()))
        # each point's entry length l: it carries load from l/2 above the surface to its full value l/2 below
        self._entry_length = self.entry_smoothing * np.sqrt(self._weights)
        #: ``r_max + l_max / 2`` (m): the bounding sphere widened by the entry band, beyond which no point is loaded
        self.reach = self.max_radius + 0.5 * float(self._entry_length.max(initial=0.0))
        self._images = None
        self._hot_weights, self._hot_entry = self._weights, self._entry_length
        if q.mirror_images is not None:
            self._images = MirrorImages(q.mirror_images, q.mirror_signs, self._normal_arm_t, self._points_t)
            self._hot_weights = self._images.quarter(self._weights)
            self._hot_entry = self._images.quarter(self._entry_length)
        # 1 / l in the layout of the sums (the entry factor's argument; 0 with sharp entry)
        self._hot_inverse_entry = np.divide(
            1.0, self._hot_entry, out=np.zeros_like(self._hot_entry), where=self._hot_entry > 0
        )
        # the points that can be hidden, and each image's signs (k, 3), its direction in the part's frame
        self.exposure = q.exposure if exposure and q.exposure is not None and len(q.exposure.columns) else None
        self._exposure_signs = self._images.point_signs if self._images is not None else np.ones((1, 3))
        # the effects by name, as the switches of every load read them
        self._effects = SimpleNamespace(**self.effect_values())

    def effect_values(self, entry_length: float | None = None, max_radius: float | None = None) -> dict[str, Any]:
        """:func:`effect_values` of this load, with its own ``entry_length`` (m: its longest point's) and
        ``max_radius`` (m: its farthest point from the centre of mass) by default."""
        if entry_length is None:
            entry_length = float(self._entry_length.max(initial=0.0))
        return effect_values(self, entry_length, self.max_radius if max_radius is None else max_radius)

    def __len__(self) -> int:
        return len(self._weights)

    def point_arrays(self) -> dict[str, np.ndarray]:
        """The per-point arrays the load sums, in point order and read-only, for code that evaluates it elsewhere:
        ``"normal_arm"``, shape (6, n), the rows of ``[n | r x n]`` (body frame); ``"points"``, shape (3, n) (m,
        body frame, about the centre of mass); ``"weights"``, shape (n,) (m^2); ``"entry_length"``, shape (n,),
        each point's ``l`` (m; zero with sharp entry)."""
        arrays = {
            "normal_arm": self._normal_arm_t,
            "points": self._points_t,
            "weights": self._weights,
            "entry_length": self._entry_length,
        }
        views = {name: values.view() for name, values in arrays.items()}
        for view in views.values():
            view.flags.writeable = False
        return views

    def heights(self, position: np.ndarray, rotation: np.ndarray, face: FrontFace | None = None) -> np.ndarray:
        """Height (m) of every quadrature point above the front face (or ``face``); negative inside the target."""
        return self._scatter(self._heights(*self._frame(position, rotation, face)))

    def _frame(
        self, position: np.ndarray, rotation: np.ndarray, face: FrontFace | None = None
    ) -> tuple[float, float, float, float]:
        """``(h, u0, u1, u2)``: the centre's height (m) above the front face (or ``face``) and the face's normal in
        the body frame (:func:`~fem_loads.target.face_frame_scalars`)."""
        face = face or self.front_face
        return face_frame_scalars(position.tolist(), rotation.tolist(), face.normal, face.offset)

    def _heights(self, height: float, *up: float) -> np.ndarray:
        """The points' heights in the layout of the sums (the images' rows, or point order)."""
        if self._images is None:
            return height + np.array(up) @ self._points_t
        return self._images.heights(height, np.array(up), np.empty(self._images.shape))

    def _scatter(self, values: np.ndarray) -> np.ndarray:
        return values if self._images is None else self._images.scatter(values)

    def fully_embedded(self, position: np.ndarray) -> bool:
        """Whether every point carries its full load as far as depth goes (bounding sphere alone)."""
        return self._sphere(self._face_height(position))[0]

    def fully_outside(self, position: np.ndarray) -> bool:
        """Whether no point can carry load (bounding sphere)."""
        return self._sphere(self._face_height(position))[1]

    def _face_height(self, position: np.ndarray) -> float:
        return float(face_height_scalars(position.tolist(), self.front_face.normal, self.front_face.offset))

    def _sphere(self, height: float) -> tuple[bool, bool]:
        """Whether the bounding sphere, widened by the entry band, is wholly inside the target and whether wholly
        outside, with the centre ``height`` (m) above the front face."""
        return height + self.reach < 0.0, height - self.reach >= 0.0

    def lowest_height(self, position: np.ndarray, rotation: np.ndarray, face: FrontFace | None = None) -> float:
        """Height (m) of the lowest point of the loaded band above the front face (or ``face``), ``min(H - l/2)``;
        negative once any point carries load (with sharp entry, the lowest surface point)."""
        heights = self.heights(position, rotation, face)
        return float((heights - 0.5 * self._entry_length).min() if self.entry_smoothing else heights.min())

    def _width(self, speed_scale: float) -> float:
        """``W``, the contact width (m/s) at the speed scale ``U`` (:func:`.factors.contact_width_scalars`)."""
        return contact_width_scalars(self.contact_width, self.contact_incidence, speed_scale)

    def _stress(
        self, frame: tuple[float, ...], velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """``sigma_n`` (Pa) and ``Vn`` (m/s) in the layout of the sums; ``frame`` is the :meth:`_frame`."""
        # Vn: the generalised velocity (R^T V, omega) times [n | r x n]; U = |V| + |omega| r_max bounds every speed
        body_velocity = velocity @ rotation
        generalised = np.concatenate([body_velocity, angular_velocity])
        if self._images is None:
            normal_velocity = generalised @ self._normal_arm_t
        else:
            normal_velocity = self._images.normal_velocity(generalised, np.empty(self._images.shape))
        speed = math.sqrt(float(velocity @ velocity))
        speed_scale = speed_scale_scalars(speed, math.sqrt(float(angular_velocity @ angular_velocity)), self.max_radius)
        # every point's depth, even wholly inside, for a law that depends on it (layers always do)
        needs_depth = self.law.depth_dependent or self.free_surface is not None
        heights = self._heights(*frame) if needs_depth or not self._sphere(frame[0])[0] else None
        depth: np.ndarray | float = -heights if needs_depth and heights is not None else 0.0
        # the law at max(Vn, 0) with separation; a built-in law is finite everywhere, and below the one-sided
        # ramp its value is multiplied by zero, so there it is evaluated at Vn itself
        exact = not self.separation or (isinstance(self.law, ResistanceLaw) and not self._effects.contact_offset)
        law_velocity = normal_velocity if exact else law_velocity_scalars(normal_velocity, self.separation)
        if isinstance(self.law, LayeredTarget):  # the layers blended across their interfaces
            lengths = self._hot_entry if self.entry_smoothing else None
            stress = self.law.normal_stress(law_velocity, np.broadcast_to(depth, normal_velocity.shape), lengths)
        else:
            stress = self.law.normal_stress(law_velocity, depth)
        guard = self.normal_velocity_guard * speed_scale
        switches = switches_scalars(self._effects, self._width(speed_scale), guard, heights is not None, False, False)
        stress = point_stress_scalars(stress, normal_velocity, depth, heights, self._hot_inverse_entry, switches)
        if self.exposure is not None:
            self._expose(stress, body_velocity)
        return stress, normal_velocity

    def _expose(self, values: np.ndarray, body_velocity: np.ndarray) -> None:
        """Multiply ``values`` (the layout of the sums) by the exposure in the body's direction of motion, turned into
        the part's frame by each image's signs: only the points its cell lists (:meth:`Exposure.hidden`)."""
        assert self.exposure is not None  # called only with a table
        if not body_velocity.any():
            return  # no direction of motion, no shadow
        rows = values[None, :] if self._images is None else values  # a view: (k, m)
        for image, signs in enumerate(self._exposure_signs):
            hidden, exposure = self.exposure.hidden(body_velocity * signs)
            rows[image, self.exposure.columns[hidden]] *= exposure

    def stress(
        self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Normal stress ``sigma_n`` (Pa) and normal velocity ``Vn`` (m/s) at every point.

        Parameters
        ----------
        position : ndarray, shape (3,)
            Centre of mass in the world frame (m).
        velocity : ndarray, shape (3,)
            Centre-of-mass velocity in the world frame (m/s).
        rotation : ndarray, shape (3, 3)
            Body-to-world rotation matrix.
        angular_velocity : ndarray, shape (3,)
            Angular velocity in the body frame (rad/s).
        """
        stress, normal_velocity = self._stress(self._frame(position, rotation), velocity, rotation, angular_velocity)
        return self._scatter(stress), self._scatter(normal_velocity)

    def surface_stress(
        self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> SurfaceStress:
        """``sigma_n``, ``tau``, ``Vn`` and the exposure at every point, in point order (see :meth:`stress`): the
        numbers the load sums, for renderings and field plots."""
        sigma, normal_velocity = self.stress(position, velocity, rotation, angular_velocity)
        tau = None
        if self.friction is not None:
            slip, scale, _ = self.slip(normal_velocity, velocity @ rotation, angular_velocity)
            tau = self.friction.stress(sigma) * scale * slip
        exposure = np.ones_like(sigma)
        if self.exposure is not None:
            rows = np.ones(self._images.shape if self._images is not None else len(sigma))
            self._expose(rows, velocity @ rotation)
            exposure = self._scatter(rows)
        return SurfaceStress(sigma, tau, normal_velocity, exposure)

    def __call__(
        self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Resultant load.

        Returns
        -------
        force : ndarray, shape (3,)
            Force on the projectile in the world frame (N).
        moment : ndarray, shape (3,)
            Moment about the centre of mass in the body frame (N m).
        """
        frame = self._frame(position, rotation)
        if self._sphere(frame[0])[1]:
            return np.zeros(3), np.zeros(3)  # fully outside
        sigma, normal_velocity = self._stress(frame, velocity, rotation, angular_velocity)
        if self._images is None:
            load = -(self._normal_arm_t @ (sigma * self._weights))
        else:
            load = self._images.negative_resultant(sigma * self._hot_weights)
        if self.friction is not None:
            sigma, normal_velocity = self._scatter(sigma), self._scatter(normal_velocity)
            load += self._friction_load(sigma, normal_velocity, velocity @ rotation, angular_velocity)
        return rotation @ load[:3], load[3:]

    def slip(
        self, normal_velocity: np.ndarray, velocity_body: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The slip speed ``|s_i|`` at every point, the factor ``k_i`` of the tangential stress ``tau_i k_i s_i``
        (:func:`~fem_loads.target.slip_factor_scalars`) and ``r_i . omega``.

        ``|s|^2 = |u|^2 - Vn^2`` with ``|u|^2 = |V|^2 + 2 r . (V x omega) + |omega|^2 |r|^2 - (omega . r)^2``.
        """
        v, w, points = velocity_body, angular_velocity, self._points
        r_dot_w = points @ w
        speed2 = float(v @ v) + 2.0 * (points @ np.cross(v, w)) + float(w @ w) * self._radius2 - r_dot_w**2  # |u|^2
        slip2 = np.maximum(speed2 - normal_velocity**2, 0.0)
        width = self._width(speed_scale_scalars(math.sqrt(float(v @ v)), math.sqrt(float(w @ w)), self.max_radius))
        return np.sqrt(slip2), slip_factor_scalars(slip2, width, float(v @ v)), r_dot_w

    def _friction_load(
        self, sigma: np.ndarray, normal_velocity: np.ndarray, velocity_body: np.ndarray, angular_velocity: np.ndarray
    ) -> np.ndarray:
        """Force and moment (body frame) of the tangential stress, opposite to the local slip: with
        ``c_i = tau_i k_i w_i`` (:meth:`slip`), ``F = -sum c_i s_i`` and ``M = -sum c_i r_i x s_i`` expanded into
        products over cached arrays (no per-point cross products)."""
        v, w, points = velocity_body, angular_velocity, self._points
        _, scale, r_dot_w = self.slip(normal_velocity, v, w)
        assert self.friction is not None  # called only with friction
        c = self.friction.stress(sigma) * self._weights * scale
        c_vn = c * normal_velocity
        sum_cr = c @ points
        force = v * float(c.sum()) + np.cross(w, sum_cr) - c_vn @ self._normals
        moment = (
            np.cross(sum_cr, v) + w * float(c @ self._radius2) - (c * r_dot_w) @ points - c_vn @ self._normal_arm[:, 3:]
        )
        return -np.concatenate([force, moment])


def effect_values(loads: Any, entry_length: float, max_radius: float) -> dict[str, Any]:
    """The effects of ``loads`` (a :class:`DAFLLoads`, or an object with its effect attributes) by name, in SI
    numbers, with the entry length ``entry_length`` (m; 0 sharp) and the body's ``max_radius`` (m): what the
    switches of every load read, and the fields of the kernels' effects record that are not the kernels' own
    (:func:`~fem_loads.kernels.records.pack_effects`)."""
    friction, surface, face = loads.friction, loads.free_surface, loads.front_face
    return {
        "contact_width": loads.contact_width,
        "contact_incidence": loads.contact_incidence,
        "contact_offset": 0.5 if loads.contact == "centred" else 0.0,
        "smooth_contact": loads.contact_width > 0.0 or loads.contact_incidence > 0.0,
        "guard": loads.normal_velocity_guard,
        "separation": loads.separation,
        "smooth_entry": entry_length > 0.0,
        "entry_length": entry_length,
        "friction": friction.coefficient if friction is not None else 0.0,
        "friction_cap": (friction.cap or 0.0) if friction is not None else 0.0,
        "surface_depth": surface.depth if surface is not None else 0.0,
        "surface_fraction": surface.surface_fraction if surface is not None else 0.0,
        "surface_front": surface.front if surface is not None else True,
        "surface_rear": surface.rear_face if surface is not None else math.inf,
        "max_radius": max_radius,
        "reach": max_radius + 0.5 * entry_length,
        "needs_depth": bool(loads.law.depth_dependent),
        "face_normal": face.normal,
        "face_offset": face.offset,
    }
