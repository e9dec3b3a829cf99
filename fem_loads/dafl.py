"""Differential area force law (DAFL): resultant target loads on a rigid projectile.

For each surface quadrature point with outward normal ``n`` at ``r`` from the centre of mass, moving with
``u = V + omega x r``:

* ``Vn = u . n`` (positive when the element pushes into the target);
* ``sigma_n = f(Vn, z) c(Vn) g(z) e(H) x``, the pipeline of :func:`~fem_loads.factors.point_stress_scalars`:
  ``f`` the target's law at the point's depth ``z`` (:func:`~fem_loads.resistance.normal_stress_scalars`, of
  which the paper's cavity expansion ``A sigma_0 + B rho_0 Vn^2`` is one case; a user's law; or the layers'
  laws blended across their interfaces), ``c`` the contact factor over the contact width ``W``, ``g`` the
  optional free-surface reduction, ``e`` the entry factor over the point's own extent ``l`` at its height ``H``
  above the target's front face (:class:`~fem_loads.target.FrontFace`, the level half-space ``Z < 0`` by
  default), and ``x`` the exposure (:mod:`fem_loads.exposure`, 1 on a convex body);
* ``dF = -sigma_n n dS``, ``F = sum dF``, ``M = sum r x dF``.

Both switches are the smooth step of :mod:`fem_loads.ramps` (:class:`DAFLLoads` defines their widths), so the
load is a continuous (Lipschitz, twice differentiable) function of the state wherever ``W > 0``; with zero
widths they are the sharp switches of the paper's law.  docs/model.md argues both widths and the convergence
to the sharp law as they go to zero.  All per-point work is a few passes over arrays cached at construction.

Optional effects (:mod:`fem_loads.target`): layered targets, a free-surface reduction, friction
``dF = -(sigma_n n + tau t) dS`` and, for comparison, no separation (every embedded point stays in contact
with ``max(0, f(Vn, z))``).  An absent effect costs nothing.

Mirror symmetry.  When the quadrature is mirror symmetric about the body planes ``y = 0`` and ``z = 0``, or
about one of them (``SurfaceQuadrature.mirror_images``), every per-point quantity is computed as four (or two)
rows, one per mirror image of the quarter ``y > 0, z > 0`` (or the half), and the resultant folds the images'
sums in mirrored pairs (:mod:`fem_loads.images`): a state symmetric about a plane then gives an exactly
symmetric load, whatever the summation order.  The friction load is summed over all points in their own order
(not exactly symmetric).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from .factors import Switches, point_stress_scalars
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

__all__ = ["DAFLLoads", "SurfaceStress", "CONTACT_MODELS"]


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
        ``e`` (:mod:`fem_loads.exposure`): 1 where the target reaches the point, 0 where the body ahead hides
        it, between at a shadow's edge; 1 everywhere without a table or with the effect off.
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
        Normal stress as a function of the normal velocity and the depth (for layers, each layer's law).
    normal_velocity_guard : float
        Sharp contact only (``contact_width = contact_incidence = 0``): a point carries stress only when
        ``Vn > guard * (|V| + |omega| r_max)``.  The sharp stress jumps from 0 to
        ``A sigma_0`` at ``Vn = 0``; on the shank of a projectile moving straight along
        its axis ``Vn`` is zero up to round-off, which alone would switch on a lateral
        load of the order of ``A sigma_0`` times half the shank area.
    friction : Friction, optional
        Tangential stress; none by default.
    separation : bool
        True (default): no stress where ``Vn <= 0`` (below the contact ramp).  False keeps every embedded
        point in contact, ``max(0, f(Vn, z))`` with the law's odd extension to ``Vn < 0``, for
        comparison; the loads can then do positive work.
    free_surface : FreeSurface, optional
        Reduction of the normal stress near the surface; none by default.
    contact_width : float
        ``w`` (m/s): the fixed part of the contact width ``W = w + delta U``, the normal
        velocity over which a point's stress rises from 0 to the full law;
        with friction, ``W`` is also the slip speed below which the friction stress fades
        (its direction is undefined at zero slip).
    contact_incidence : float
        ``delta``: the part of ``W`` proportional to the body's speed scale
        ``U = |V| + |omega| r_max``, the sine of the incidence angle over which the stress
        rises.  ``w = delta = 0``: sharp.
    contact : {"one_sided", "centred"}
        Where the ramp lies: ``c = S(Vn / W)``, from 0 at ``Vn = 0`` to 1 at ``Vn = W`` (one-sided: an
        element sliding along the target, ``Vn = 0``, is unloaded), or ``c = S(1/2 + Vn / W)``, centred on
        ``Vn = 0`` (half loaded there).  Two models with two different limits as ``W -> 0``
        (docs/model.md); the law is evaluated at ``max(Vn, 0)`` in both.
    entry_smoothing : float
        ``l / sqrt(weight)``: the length over which a point enters the target (and
        crosses a layer interface), in units of the square root of its quadrature weight
        (about its own size).  0: sharp.
    exposure : bool
        True (default): a point the target cannot reach, the ray from it along the body's velocity meeting
        the body (``SurfaceQuadrature.exposure``, :mod:`fem_loads.exposure`), carries no stress.  False: every
        point with a positive ``Vn`` does.  A quadrature without a table (a convex body) is unaffected.
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
        self._smooth_contact = self.contact_width > 0.0 or self.contact_incidence > 0.0
        self._contact_offset = 0.5 if contact == "centred" else 0.0
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
        self._max_radius = float(np.sqrt(self._radius2.max()))
        # each point's entry length l: it carries load from l/2 above the surface to its full value l/2 below
        self._entry_length = self.entry_smoothing * np.sqrt(self._weights)
        self._half_entry = 0.5 * float(self._entry_length.max()) if len(self._weights) else 0.0
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
        # the points that can be hidden: their positions in the part (or in every point), and each image's signs
        self.exposure = q.exposure if exposure and q.exposure is not None and len(q.exposure.columns) else None
        if self.exposure is not None:
            signs = self._images.point_signs if self._images is not None else np.ones((1, 3))
            self._exposure_signs = signs  # (k, 3): each image's direction in the part's frame

    def __len__(self) -> int:
        return len(self._weights)

    @property
    def max_radius(self) -> float:
        """``r_max`` (m): the distance of the farthest quadrature point from the centre of mass (the bounding
        sphere, and the lever of the speed scale ``U = |V| + |omega| r_max`` of the contact width)."""
        return self._max_radius

    @property
    def depth_dependent(self) -> bool:
        """Whether the target's stress depends on the depth (a law with depth-dependent strength, a user's law,
        layers): then every point's depth is needed, even with the body wholly in the target."""
        return isinstance(self.law, LayeredTarget) or bool(self.law.depth_dependent)

    def point_arrays(self) -> dict[str, np.ndarray]:
        """The per-point arrays the load sums, in point order and read-only, for code that evaluates it outside
        this class (:mod:`fem_loads.compiled`, the C loop of docs/performance/lower_bound.py): ``"normal_arm"``,
        shape (6, n), the rows of ``[n | r x n]`` (body frame); ``"points"``, shape (3, n), the points (m, body
        frame, about the centre of mass); ``"weights"``, shape (n,), the quadrature weights (m^2);
        ``"entry_length"``, shape (n,), each point's entry length ``l`` (m; zero with sharp entry)."""
        arrays = {
            "normal_arm": self._normal_arm_t,
            "points": self._points_t,
            "weights": self._weights,
            "entry_length": self._entry_length,
        }
        views: dict[str, np.ndarray] = {}
        for name, values in arrays.items():
            views[name] = values.view()
            views[name].flags.writeable = False
        return views

    # -- geometry ---------------------------------------------------------------------------------

    def heights(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """Height (m) of every quadrature point above the front face; negative inside the target."""
        return self._scatter(self._heights(position, rotation))

    def _heights(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """The heights in the layout of the sums (the images' rows, or point order)."""
        face = self.front_face
        height, *up = face_frame_scalars(position.tolist(), rotation.tolist(), face.normal, face.offset)
        if self._images is None:
            return height + np.array(up) @ self._points_t
        return self._images.heights(height, np.array(up), np.empty(self._images.shape))

    def _face_height(self, position: np.ndarray) -> float:
        """The centre of mass's height (m) above the front face."""
        return float(face_height_scalars(position.tolist(), self.front_face.normal, self.front_face.offset))

    def _scatter(self, values: np.ndarray) -> np.ndarray:
        return values if self._images is None else self._images.scatter(values)

    def fully_embedded(self, position: np.ndarray) -> bool:
        """Whether every point carries its full load as far as depth goes (bounding sphere alone)."""
        return self._face_height(position) + self._max_radius + self._half_entry < 0.0

    def fully_outside(self, position: np.ndarray) -> bool:
        """Whether no point can carry load (bounding sphere)."""
        return self._face_height(position) - self._max_radius - self._half_entry >= 0.0

    def lowest_height(self, position: np.ndarray, rotation: np.ndarray) -> float:
        """Height (m) of the lowest point of the loaded band, ``min(Z - l/2)``; negative once any point
        carries load (with sharp entry, the lowest surface point)."""
        heights = self.heights(position, rotation)
        return float((heights - 0.5 * self._entry_length).min() if self.entry_smoothing else heights.min())

    # -- the factors of the switches ---------------------------------------------------------------

    def _inverse_width(self, speed_scale: float) -> float:
        """``1 / W``, ``W = w + delta U`` the contact width (m/s) at the body speed scale
        ``U = |V| + |omega| r_max``; 0 for a body at rest with ``w = 0`` (every ``Vn`` is then 0,
        and so is the factor)."""
        width = self.contact_width + self.contact_incidence * speed_scale
        return 1.0 / width if width > 0.0 else 0.0

    def _switches(self, speed_scale: float, entering: bool) -> Switches:
        """The factors' :class:`~fem_loads.factors.Switches` at the speed scale ``U`` (m/s)."""
        surface = self.free_surface
        return Switches(
            self.separation,
            self._smooth_contact,
            self._inverse_width(speed_scale),
            self._contact_offset,
            self.normal_velocity_guard * speed_scale,
            surface is not None,
            1.0 / surface.depth if surface is not None else 0.0,
            surface.surface_fraction if surface is not None else 1.0,
            entering,
            bool(self.entry_smoothing),
        )

    def _target_stress(self, normal_velocity: np.ndarray, depth: np.ndarray | float) -> np.ndarray:
        """The target's law at every point (a new array): one law, or the layers blended across their interfaces."""
        if isinstance(self.law, LayeredTarget):
            lengths = self._hot_entry if self.entry_smoothing else None
            return self.law.normal_stress(normal_velocity, np.broadcast_to(depth, normal_velocity.shape), lengths)
        return self.law.normal_stress(normal_velocity, depth)

    # -- per point ---------------------------------------------------------------------------------

    def _stress(
        self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray, float]:
        """``sigma_n`` (Pa), ``Vn`` (m/s) in the layout of the sums, and the speed scale ``U`` (m/s)."""
        normal_velocity, speed_scale = self._normal_velocity(velocity, rotation, angular_velocity, np.empty(6))
        needs_depth = self.depth_dependent or self.free_surface is not None
        heights = None
        if needs_depth or not self.fully_embedded(position):
            heights = self._heights(position, rotation)
        depth: np.ndarray | float = -heights if needs_depth and heights is not None else 0.0
        # the law at max(Vn, 0) with separation; a built-in law is finite everywhere, and below the one-sided
        # ramp its value is multiplied by zero, so there it is evaluated at Vn itself
        exact = not self.separation or (isinstance(self.law, ResistanceLaw) and not self._contact_offset)
        stress = self._target_stress(normal_velocity if exact else np.maximum(normal_velocity, 0.0), depth)
        switches = self._switches(speed_scale, heights is not None)
        stress = point_stress_scalars(stress, normal_velocity, depth, heights, self._hot_inverse_entry, switches)
        if self.exposure is not None:
            self._expose(stress, velocity @ rotation)
        return stress, normal_velocity, speed_scale

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
        stress, normal_velocity, _ = self._stress(position, velocity, rotation, angular_velocity)
        return self._scatter(stress), self._scatter(normal_velocity)

    def surface_stress(
        self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> SurfaceStress:
        """``sigma_n``, ``tau`` and ``Vn`` at every quadrature point, in point order (see :meth:`stress`).

        The same numbers the load sums: renderings and field plots take them from here
        instead of evaluating the law again.
        """
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

    def _normal_velocity(
        self, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray, generalised: np.ndarray
    ) -> tuple[np.ndarray, float]:
        """``Vn`` at every point (one product with ``[n | r x n]``) and the body's speed scale
        ``U = |V| + |omega| r_max`` (m/s), a bound on every point's speed.

        ``generalised`` is a 6-vector to fill with ``(R^T V, omega)``.
        """
        generalised[:3] = velocity @ rotation  # R^T V
        generalised[3:] = angular_velocity
        speed = math.sqrt(float(velocity @ velocity))
        spin = math.sqrt(float(angular_velocity @ angular_velocity))
        speed_scale = speed + spin * self._max_radius
        if self._images is None:
            return generalised @ self._normal_arm_t, speed_scale
        return self._images.normal_velocity(generalised, np.empty(self._images.shape)), speed_scale

    # -- resultants ----------------------------------------------------------------------------------

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
        if self.fully_outside(position):
            return np.zeros(3), np.zeros(3)
        sigma, normal_velocity, _ = self._stress(position, velocity, rotation, angular_velocity)
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
        """The slip speed ``|s_i|`` at every point, the factor ``k_i`` that gives the friction stress's
        share along the slip (``tau_i k_i s_i`` is the tangential stress vector) and ``r_i . omega``.

        ``s_i = V + omega x r_i - Vn_i n_i``, with ``|s|^2 = |u|^2 - Vn^2`` and
        ``|u|^2 = |V|^2 + 2 r . (V x omega) + |omega|^2 |r|^2 - (omega . r)^2`` (no per-point
        cross products).  With a contact width ``W`` the direction fades below ``W`` of slip,
        ``k = 1 / sqrt(|s|^2 + W^2)``, so the stress is continuous through zero slip; sharp,
        ``k = 1/|s|`` where ``|s| > 1e-12 |V|`` and 0 elsewhere (the direction is undefined at zero).
        """
        v, w = velocity_body, angular_velocity
        r_dot_w = self._points @ w
        speed2 = (
            float(v @ v)
            + 2.0 * (self._points @ np.cross(v, w))
            + float(w @ w) * self._radius2
            - r_dot_w**2
            - normal_velocity**2
        )
        slip2 = np.maximum(speed2, 0.0)
        width = 0.0
        if self._smooth_contact:
            # a body at rest with w = 0 has no width (and no slip)
            inverse = self._inverse_width(math.sqrt(float(v @ v)) + math.sqrt(float(w @ w)) * self._max_radius)
            width = 1.0 / inverse if inverse > 0.0 else 0.0
        return np.sqrt(slip2), slip_factor_scalars(slip2, width, float(v @ v)), r_dot_w

    def _friction_load(
        self, sigma: np.ndarray, normal_velocity: np.ndarray, velocity_body: np.ndarray, angular_velocity: np.ndarray
    ) -> np.ndarray:
        """Force and moment (body frame) of the tangential stress, opposite to the local slip.

        With ``c_i = tau_i k_i w_i`` (:meth:`slip`) and the slip ``s_i``, ``F = -sum c_i s_i`` and
        ``M = -sum c_i r_i x s_i`` expand into weighted sums (``sum c``, ``sum c r``, ``sum c |r|^2``,
        ``sum c r (r . omega)``, ``sum c Vn n``, ``sum c Vn r x n``): matrix-vector products over
        cached arrays, no per-point cross products.
        """
        v, w = velocity_body, angular_velocity
        points = self._points
        _, scale, r_dot_w = self.slip(normal_velocity, v, w)
        assert self.friction is not None  # called only with friction
        c = self.friction.stress(sigma) * self._weights * scale
        c_vn = c * normal_velocity
        sum_c = float(c.sum())
        sum_cr = c @ points
        force = v * sum_c + np.cross(w, sum_cr) - c_vn @ self._normals
        moment = (
            np.cross(sum_cr, v) + w * float(c @ self._radius2) - (c * r_dot_w) @ points - c_vn @ self._normal_arm[:, 3:]
        )
        return -np.concatenate([force, moment])
