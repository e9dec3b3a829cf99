"""Independent references for normal impact: the closed form and a 1-D integration.

For a rigid axisymmetric projectile moving straight along its axis into the
target (no friction), an element at distance ``s`` behind the tip has
``Vn = V sin(slope)``, so the axial force with the nose embedded to depth
``P`` is

    F(P, V) = pi r(P')^2 A sigma_0 + B rho_0 V^2 G(P'),
    G(P) = int_0^P 2 pi r r' r'^2 / (1 + r'^2) ds,   P' = min(P, nose length),

and ``G`` of the whole nose is ``pi a^2 N``.  Once the nose is embedded the
motion has a closed form (docs/validation.md).  With a contact width ``w``
(the stress of an element rises from 0 at ``Vn = 0`` to the full law at
``Vn = W = w + delta V``, :func:`fem_loads.factors.smooth_step_scalars`) the force is

    F(P, V) = int_0^P' 2 pi r r' (A sigma_0 + B rho_0 V^2 sin^2) S(V sin / W) ds,

which is no longer separable: the whole run is integrated, the integral over
the nose taken by Gauss-Legendre quadrature.  None of this uses the mesh.

A measured body behind the nose (``projectile.body``) is covered when it only narrows (a boat tail:
its surface faces backward and never presses in axial motion); a flare faces forward and presses,
and these references refuse it (:func:`check_nose_alone_presses`).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Callable
from typing import TYPE_CHECKING, Any, NamedTuple

import numpy as np
from scipy import integrate, optimize
from scipy.interpolate import BarycentricInterpolator

from fem_loads.factors import contact_factor_scalars, contact_width_scalars
from fem_loads.resistance import ResistanceLaw
from fem_loads.target import GAP, LayeredTarget
from fem_loads.user_law import UserLaw
from mesh.profile import ConeNose, OgiveNose, Profile

if TYPE_CHECKING:
    from ..run import PreparedProjectile
    from ..scene import Scene

__all__ = [
    "is_plain_normal_impact",
    "embedded_axial_force",
    "closed_form_depth",
    "axial_depth_1d",
    "scene_depth_1d",
    "axial_force",
    "nose_factors",
    "check_nose_alone_presses",
    "Layer",
    "target_layers",
    "scene_slices",
    "scene_slab_1d",
    "layered_axial_force",
    "slab_run_1d",
    "ballistic_limit_1d",
]


def check_nose_alone_presses(profile: Profile) -> None:
    """Raise ValueError when anything behind the nose faces forward (a flare): these references load the nose
    and the tip face only."""
    if profile.body is None:
        return
    curve = profile.body_curve
    assert curve is not None  # a measured body has its curve
    s = np.linspace(profile.body.start, profile.length, 2001)
    if float(curve.slope(s).max()) > 0.0 or float(curve.r.max()) > profile.radius:
        raise ValueError(
            "projectile.body: a flare presses in axial motion, and the 1-D references load the nose"
            " alone (a boat tail, which only narrows, is covered)"
        )


def is_plain_normal_impact(scene: Scene) -> bool:
    """A normal impact with no disturbance, one law and no effect, of a body of revolution whose nose alone
    presses (no flare): the 1-D integration is its exact reference."""
    impact, effects = scene.impact, scene.effects
    plain = (
        impact.oblique_angle == 0
        and impact.attack_angle == 0
        and impact.yaw_angle == 0
        and not any(impact.angular_velocity)
        and scene.target.layers is None
        and effects.friction.model == "none"
        and effects.separation
        and effects.free_surface is None
        and not effects.gravity
        and scene.projectile.geometry is None
    )
    if plain and scene.projectile.body is not None:
        try:
            check_nose_alone_presses(scene.projectile.profile())
        except ValueError:
            return False
    return plain


def nose_factors(profile: Profile, friction: float = 0.0) -> tuple[float, float]:
    """Nose factors ``(N1, N2)`` with Coulomb friction ``mu``: ``F = pi a^2 (N1 A sigma_0 + N2 B rho_0 V^2)``.

    For axial motion an element of the nose slips along its meridian, so the
    friction ``mu sigma_n`` adds ``mu sigma_n cos(slope)`` to the axial drag:
    ``N1 = 1 + mu int 2 pi r ds / (pi a^2)`` and
    ``N2 = N + mu int 2 pi r sin^2(slope) ds / (pi a^2)``.  Closed forms:

    * tangent ogive, CRH ``psi`` (``R = 2 psi a``, nose length ``L``):
      ``N1 = 1 + mu [4 psi^2 asin(L/R) - (2 psi - 1) sqrt(4 psi - 1)]``,
      ``N2 = (8 psi - 1)/(24 psi^2) + mu (2/(a^2 R^2)) [L (2 L^2 - R^2)(R - a)/8
      + R^4 asin(L/R)/8 - (R - a) L^3/3]``;
    * cone of half-angle ``theta``: ``N1 = 1 + mu cot(theta)``,
      ``N2 = sin^2(theta) + mu sin(theta) cos(theta)``.
    """
    check_nose_alone_presses(profile)
    a, ln = profile.radius, profile.nose_length
    if isinstance(profile.nose, OgiveNose):
        psi, big_r = profile.nose.crh, profile.ogive_radius
        n1 = 1 + friction * (4 * psi**2 * math.asin(ln / big_r) - (2 * psi - 1) * math.sqrt(4 * psi - 1))
        bracket = (
            ln * (2 * ln**2 - big_r**2) * (big_r - a) / 8
            + big_r**4 * math.asin(ln / big_r) / 8
            - (big_r - a) * ln**3 / 3
        )
        n2 = profile.nose_factor() + friction * 2 / (a**2 * big_r**2) * bracket
        return n1, n2
    if isinstance(profile.nose, ConeNose):
        theta = math.radians(profile.nose.half_angle)
        return 1 + friction / math.tan(theta), math.sin(theta) ** 2 + friction * math.sin(theta) * math.cos(theta)

    # other noses: the same integrals, by quadrature (a flat front face does not slip axially)
    def sin2(s: float) -> float:
        slope = float(profile.slope_at(s))
        return slope**2 / (1 + slope**2)

    area = math.pi * a**2
    kinks = {
        "points": [p for p in profile.breakpoints if p < ln] or None,
        "limit": max(200, 4 * len(profile.breakpoints)),
    }
    side = integrate.quad(lambda s: 2 * math.pi * float(profile.radius_at(s)), 0, ln, epsrel=1e-12, **kinks)[0]
    dyn = integrate.quad(lambda s: 2 * math.pi * float(profile.radius_at(s)) * sin2(s), 0, ln, epsrel=1e-12, **kinks)[0]
    return 1 + friction * side / area, profile.nose_factor() + friction * dyn / area


def _g(profile: Profile, depth: float) -> float:
    def integrand(s: float) -> float:
        slope = float(profile.slope_at(s))
        return 2 * math.pi * float(profile.radius_at(s)) * slope**3 / (1 + slope**2)

    # a flat front face (blunt nose) meets the target head on: sin(slope) = 1 there
    end = min(depth, profile.nose_length)
    kinks = [p for p in profile.breakpoints if 0.0 < p < end] or None  # a measured nose's points
    return (
        math.pi * profile.tip_radius**2
        + integrate.quad(
            integrand, 0.0, end, points=kinks, epsabs=0, epsrel=1e-13, limit=max(200, 4 * len(kinks or ()))
        )[0]
    )


def embedded_axial_force(profile: Profile, law: ResistanceLaw, speed: float, friction: float = 0.0) -> float:
    """Axial force (N) on a fully embedded nose: ``pi a^2 (N1 A sigma_0 + N2 B rho_0 V^2)``.

    Without friction ``N1 = 1`` and ``N2 = N``; see :func:`nose_factors`.
    """
    n1, n2 = nose_factors(profile, friction)
    return math.pi * profile.radius**2 * (n1 * law.c0 + n2 * law.c2 * speed**2)


def closed_form_depth(profile: Profile, law: ResistanceLaw, mass: float, speed: float) -> float:
    """Distance (m) travelled after full embedding at ``speed`` (m/s), to rest.

    ``P = m / (2 pi a^2 N B rho_0) ln(1 + N B rho_0 V1^2 / (A sigma_0))``.
    """
    check_nose_alone_presses(profile)
    area = math.pi * profile.radius**2
    n_b = profile.nose_factor() * law.c2
    return mass / (2 * area * n_b) * math.log1p(n_b * speed**2 / law.c0)


def axial_depth_1d(
    profile: Profile,
    law: ResistanceLaw | UserLaw,
    mass: float,
    speed: float,
    stop_speed: float = 0.0,
    rtol: float = 1e-12,
    contact_width: float = 0.0,
    contact_incidence: float = 0.0,
    contact: str = "one_sided",
) -> tuple[float, float]:
    """Tip depth (m) at which the speed falls to ``stop_speed``, with exact nose entry.

    Integrates ``dP/dt = V, m dV/dt = -F(P, V)`` through the nose-entry phase
    (``G`` interpolated to round-off on Chebyshev points); after full
    embedding the closed form takes over exactly.  With a contact width
    ``w + delta V > 0`` (``contact_width``, ``contact_incidence``, the ramp ``contact``), or a law
    other than cavity expansion, the whole run is integrated with the force of :func:`axial_force`.

    Returns
    -------
    depth : float
        Tip depth at ``stop_speed`` (m).
    embedding_speed : float
        Speed (m/s) when the nose is fully embedded.
    """
    check_nose_alone_presses(profile)
    cavity = isinstance(law, ResistanceLaw) and law.c1 == law.c == 0.0 and not law.depth_dependent
    if contact_width > 0.0 or contact_incidence > 0.0 or not isinstance(law, ResistanceLaw) or not cavity:
        ramp = (contact_width, contact_incidence, contact)
        return _axial_depth_contact(profile, law, mass, speed, stop_speed, rtol, *ramp)
    ln = profile.nose_length
    # G is smooth on the nose: tabulate it once on Chebyshev points for a fast, exact-to-rtol integrand
    nodes = 0.5 * ln * (1 - np.cos(np.linspace(0, math.pi, 401)))
    g_nodes = np.array([_g(profile, p) for p in nodes])
    g_interp = BarycentricInterpolator(nodes, g_nodes)

    def rate(t: float, y: np.ndarray) -> list[float]:
        p = min(max(y[0], 0.0), ln)
        force = math.pi * float(profile.radius_at(p)) ** 2 * law.c0
        force += law.c2 * y[1] ** 2 * float(g_interp(p))
        return [y[1], -force / mass]

    sol = _integrate(rate, [0.0, speed], stop_speed, rtol, embedded_at=ln)
    if len(sol.t_events[0]) == 0:  # stopped before full embedding
        return float(sol.y[0, -1]), float("nan")
    v1 = float(sol.y_events[0][0][1])
    # after embedding: P(V) in closed form between v1 and stop_speed
    rest = closed_form_depth(profile, law, mass, v1) - closed_form_depth(profile, law, mass, stop_speed)
    return ln + rest, v1


def scene_depth_1d(scene: Scene, prepared: PreparedProjectile) -> float:
    """:func:`axial_depth_1d` of a scene's normal impact: its projectile's profile and mass, its law, impact speed,
    stop speed and contact ramp (the tip depth, m)."""
    law = scene.target.build()
    assert not isinstance(law, LayeredTarget)  # a normal impact into one law (built-in or a user's)
    depth, _ = axial_depth_1d(
        prepared.profile,
        law,
        prepared.mass.mass,
        scene.impact.speed,
        scene.stop_speed,
        **scene.effects.contact_ramp,
    )
    return depth


def _integrate(
    rate: Callable[[float, np.ndarray], list[float]],
    start: list[float],
    stop_speed: float,
    rtol: float,
    embedded_at: float | None = None,
) -> Any:  # scipy's OdeResult (scipy has no types here)
    """``solve_ivp`` of ``(P, V)`` from ``start`` until the speed falls to ``stop_speed`` or, with
    ``embedded_at`` (the nose length), the nose is embedded (events ``[embedded, stopped]``, else
    ``[stopped]``)."""

    def stopped(t: float, y: np.ndarray) -> float:
        return y[1] - stop_speed

    stopped.terminal = True  # type: ignore[attr-defined]  # solve_ivp reads this attribute of an event function
    events, horizon = [stopped], 1e3
    if embedded_at is not None:

        def embedded(t: float, y: np.ndarray) -> float:
            return y[0] - embedded_at

        embedded.terminal = True  # type: ignore[attr-defined]  # as stopped's
        events, horizon = [embedded, stopped], 10 * embedded_at / start[1] + 1.0
    return integrate.solve_ivp(rate, (0.0, horizon), start, method="DOP853", rtol=rtol, atol=1e-14, events=events)


@functools.cache
def _gauss(points: int) -> tuple[np.ndarray, np.ndarray]:
    """Gauss-Legendre nodes and weights on [-1, 1], computed on first use (2000 points take half a second, which
    every process importing this module would pay)."""
    return np.polynomial.legendre.leggauss(points)


def axial_force(
    profile: Profile,
    law: ResistanceLaw | UserLaw,
    depth: float,
    speed: float,
    contact_width: float,
    contact_incidence: float = 0.0,
    contact: str = "one_sided",
) -> float:
    """Axial force (N) with the nose tip at ``depth`` (m) at ``speed`` (m/s), with the contact width
    ``W = w + delta V`` (m/s; ``w = contact_width``, ``delta = contact_incidence``; 0: sharp) and ramp ``contact``.

    ``int_0^P' 2 pi r r' f(V sin, P - s) c(V sin / W) ds`` by 2000-point Gauss-Legendre quadrature over the
    embedded part of the nose (``s`` from the tip, ``f`` the law at the element's normal velocity and depth,
    ``c`` the contact factor: ``S(x)`` one-sided, ``S(1/2 + x)`` centred, the step ``x > 0`` sharp), plus a
    flat front face (``sin = 1``) of a blunt nose.  The shank (``Vn = 0``) carries no axial force.
    """
    width = contact_width_scalars(contact_width, contact_incidence, speed)
    offset = 0.5 if contact == "centred" else 0.0
    extent = min(max(depth, 0.0), profile.nose_length)
    x, weights = _gauss(2000)
    s = 0.5 * extent * (x + 1.0)
    slope = profile.slope_at(s)
    sine = slope / np.sqrt(1.0 + slope**2)

    def factor(normal_velocity: np.ndarray) -> np.ndarray:
        return np.asarray(
            contact_factor_scalars(normal_velocity, width > 0.0, 1.0 / width if width > 0.0 else 0.0, offset, 0.0)
        )

    stress = law.normal_stress(speed * sine, depth - s) * factor(speed * sine)
    force = 0.5 * extent * float(np.sum(weights * 2 * np.pi * profile.radius_at(s) * slope * stress))
    if depth < 0.0 or profile.tip_radius == 0.0:
        return force
    face = float(law.normal_stress(np.array([speed]), depth)[0] * factor(np.array([speed]))[0])
    return force + math.pi * profile.tip_radius**2 * face


def _axial_depth_contact(
    profile: Profile,
    law: ResistanceLaw | UserLaw,
    mass: float,
    speed: float,
    stop_speed: float,
    rtol: float,
    contact_width: float,
    contact_incidence: float,
    contact: str,
) -> tuple[float, float]:
    def rate(t: float, y: np.ndarray) -> list[float]:
        return [y[1], -axial_force(profile, law, y[0], y[1], contact_width, contact_incidence, contact) / mass]

    entry = _integrate(rate, [0.0, speed], stop_speed, rtol, embedded_at=profile.nose_length)
    if len(entry.t_events[0]) == 0:
        return float(entry.y[0, -1]), float("nan")
    p1, v1 = (float(v) for v in entry.y_events[0][0])
    # embedded: F depends on V alone; integrate until the speed falls to stop_speed
    rest = _integrate(rate, [p1, v1], stop_speed, rtol)
    return float(rest.y_events[0][0][0]) if len(rest.t_events[0]) else float(rest.y[0, -1]), v1


class Layer(NamedTuple):
    """A slice of the target along the axis of a normal impact: from ``top`` to ``bottom`` (m below the front face;
    ``bottom`` may be ``inf``) with its ``law``, or None for a gap."""

    top: float
    bottom: float
    law: ResistanceLaw | UserLaw | None


def target_layers(thicknesses: list[float | None], laws: list[ResistanceLaw | UserLaw | None]) -> list[Layer]:
    """The :class:`Layer` slices of layers given front to back by their thicknesses (m; None for the last: it
    goes on forever) and laws (None: a gap)."""
    layers, top = [], 0.0
    for thickness, law in zip(thicknesses, laws):
        bottom = math.inf if thickness is None else top + thickness
        layers.append(Layer(top, bottom, law))
        top = bottom
    return layers


def scene_slices(scene: Scene) -> list[Layer]:
    """The :class:`Layer` slices of a scene's target: each layer's law as the scene builds it, None for a gap."""
    built = scene.target.build()
    if not isinstance(built, LayeredTarget):
        return target_layers([None], [built])
    layers = scene.target.layers or []
    return target_layers(
        [layer.thickness for layer in layers], [None if law is GAP else law for law in built.laws[: len(layers)]]
    )


def scene_slab_1d(scene: Scene, prepared: PreparedProjectile) -> tuple[float, float]:
    """:func:`slab_run_1d` of a scene's normal impact: its projectile's profile and mass, its target's slices, its
    impact speed, stop speed and contact ramp (the residual velocity, m/s, NaN if the body stops; the tip depth, m)."""
    return slab_run_1d(
        prepared.profile,
        scene_slices(scene),
        prepared.mass.mass,
        scene.impact.speed,
        scene.stop_speed,
        **scene.effects.contact_ramp,
    )


def layered_axial_force(
    profile: Profile,
    layers: list[Layer],
    depth: float,
    speed: float,
    contact_width: float = 0.0,
    contact_incidence: float = 0.0,
    contact: str = "one_sided",
) -> float:
    """Axial force (N) on the nose with its tip ``depth`` (m) below the front face at ``speed`` (m/s) in a target of
    :class:`Layer` slices with sharp faces: :func:`axial_force`'s integral taken over the part of the nose inside
    each slice by its own 400-point Gauss-Legendre rule (the integrand jumps at each face), gaps and the space
    behind the last slice unloaded.  An element ``s`` behind the tip lies ``depth - s`` deep."""
    width = contact_width_scalars(contact_width, contact_incidence, speed)
    offset = 0.5 if contact == "centred" else 0.0
    x, weights = _gauss(400)

    def factor(normal_velocity: np.ndarray) -> np.ndarray:
        return np.asarray(
            contact_factor_scalars(normal_velocity, width > 0.0, 1.0 / width if width > 0.0 else 0.0, offset, 0.0)
        )

    force = 0.0
    for layer in layers:
        if layer.law is None:
            continue
        start, end = max(0.0, depth - layer.bottom), min(profile.nose_length, depth - layer.top)
        if end > start:
            s = start + 0.5 * (end - start) * (x + 1.0)
            slope = profile.slope_at(s)
            normal_velocity = speed * slope / np.sqrt(1.0 + slope**2)
            stress = layer.law.normal_stress(normal_velocity, depth - s) * factor(normal_velocity)
            force += 0.5 * (end - start) * float(np.sum(weights * 2 * np.pi * profile.radius_at(s) * slope * stress))
        if profile.tip_radius > 0.0 and layer.top < depth < layer.bottom:  # a blunt nose's flat face, head on
            face = float(layer.law.normal_stress(np.array([speed]), depth)[0] * factor(np.array([speed]))[0])
            force += math.pi * profile.tip_radius**2 * face
    return force


def slab_run_1d(
    profile: Profile,
    layers: list[Layer],
    mass: float,
    speed: float,
    stop_speed: float = 0.0,
    rtol: float = 1e-10,
    **contact_ramp: Any,
) -> tuple[float, float]:
    """A normal impact at ``speed`` (m/s) into the :class:`Layer` slices, integrated along the axis
    (``dP/dt = V, m dV/dt = -F(P, V)``, :func:`layered_axial_force`, ``contact_ramp`` its contact keywords) until
    the speed falls to ``stop_speed`` or the whole nose has passed the last slice's rear face (nothing behind the
    nose presses in axial motion).

    Returns
    -------
    residual_velocity : float
        The speed (m/s) once the nose is through, NaN if the body stopped.
    depth : float
        The tip's depth (m) at the end.
    """
    check_nose_alone_presses(profile)
    rear = max(layer.bottom for layer in layers if layer.law is not None)
    if math.isinf(rear):
        raise ValueError("the target has no rear face: the body cannot pass through it")

    def rate(t: float, y: np.ndarray) -> list[float]:
        return [y[1], -layered_axial_force(profile, layers, y[0], y[1], **contact_ramp) / mass]

    # the force has kinks where a face passes the tip or the nose's base: stop at each and start again
    kinks = sorted(
        {top + at for layer in layers for top in (layer.top, layer.bottom) for at in (0.0, profile.nose_length)}
    )
    state = [0.0, speed]
    for kink in [k for k in kinks if 0.0 < k <= rear + profile.nose_length]:
        if state[0] >= kink:
            continue
        run = _integrate(rate, state, stop_speed, rtol, embedded_at=kink)
        if len(run.t_events[0]) == 0:
            return math.nan, float(run.y[0, -1]) if len(run.t_events[1]) == 0 else float(run.y_events[1][0][0])
        state = [float(v) for v in run.y_events[0][0]]
    return state[1], state[0]


def ballistic_limit_1d(
    profile: Profile, layers: list[Layer], mass: float, relative: float = 1e-6, **contact_ramp: Any
) -> float:
    """The lowest speed (m/s) at which :func:`slab_run_1d` passes the nose through the slices, by bisection
    (``scipy.optimize.bisect``) to ``relative``: below it the body stops inside."""
    runs: dict[float, float] = {}  # the bracket's ends, run once: bisect evaluates both ends again

    def passes(speed: float) -> float:
        if speed not in runs:
            runs[speed] = -1.0 if math.isnan(slab_run_1d(profile, layers, mass, speed, **contact_ramp)[0]) else 1.0
        return runs[speed]

    low, high = 1.0, 100.0
    while passes(low) > 0.0:
        low /= 10.0  # a target so thin that even this speed goes through
    while passes(high) < 0.0:
        low, high = high, 2.0 * high

    return float(optimize.bisect(passes, low, high, rtol=relative))
