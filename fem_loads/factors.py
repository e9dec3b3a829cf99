"""The factors of a surface point's stress, each defined once.

The DAFL stress of a point is its target's law times factors, and its friction stress a function of that:

    sigma = f(Vn, z) c(Vn) g(z) e(H) x,    tau = min(mu sigma, tau_s)

with ``c`` the contact factor, ``g`` the free-surface reduction (at the distance from the nearest free face it
applies at), ``e`` the entry factor, ``x`` the exposure (:func:`fem_loads.exposure.cell_exposure_scalars`) and
``tau`` the friction stress, along the slip by :func:`fem_loads.target.slip_factor_scalars`.

Each is written on floats and numpy arrays alike: the numpy path evaluates it on every point at once, and
:mod:`fem_loads.kernels.native` compiles the same function for the compiled kernels.  A flag is one value for all the
points, so a compiled loop that passes a constant keeps no branch.  :func:`point_stress_scalars` is the pipeline
every load calls; a new factor is one ``*_scalars`` function here and one line in it.

The ramps (the contact, entry and free-surface factors, and the layers' blend) are the quintic smooth step
``S(t) = t^3 (10 - 15 t + 6 t^2)`` on [0, 1], 0 below and 1 above (:func:`smooth_step_scalars`): two continuous
derivatives, so that a Runge-Kutta step across a switch keeps its order, and slope at most ``S'(1/2) = 15/8``
(docs/model.md).
"""

from __future__ import annotations

import math
from typing import Any, NamedTuple

import numpy as np

__all__ = [
    "smooth_step_scalars",
    "add_term",
    "MAX_SLOPE",
    "Switches",
    "switches_scalars",
    "point_stress_scalars",
    "contact_factor_scalars",
    "entry_factor_scalars",
    "layer_share_scalars",
    "surface_factor_scalars",
    "free_face_distance_scalars",
    "friction_stress_scalars",
]

MAX_SLOPE = 15.0 / 8.0  # the largest dS/dt, at t = 1/2


def smooth_step_scalars(t: Any) -> Any:
    """``S(clip(t, 0, 1))`` on a float or an array."""
    t = np.clip(t, 0.0, 1.0)  # on an array one pass where maximum then minimum take two
    # t^3 (10 + t (6 t - 15)); on an array the augmented operations work in place (no temporaries)
    step = 6.0 * t
    step -= 15.0
    step *= t
    step += 10.0
    step *= t
    step *= t
    step *= t
    return step


def add_term(value: Any, term: float) -> Any:
    """``value + term``: on an array in place, and skipped where ``term`` is 0 (an array pass fewer).  Compiled
    (:mod:`fem_loads.kernels.native`) it is always added, so that a loop over the points keeps no branch."""
    if term != 0.0:
        value += term
    return value


class Switches(NamedTuple):
    """What the factors of every point share in one load evaluation (:func:`point_stress_scalars`)."""

    separation: bool  #: no stress below the contact ramp (else ``max(f, 0)`` everywhere)
    smooth_contact: bool  #: the contact ramp (else the sharp switch at ``Vn > threshold``)
    inverse_width: float  #: ``1 / W`` (s/m; 0 for a body at rest without a fixed width)
    contact_offset: float  #: 0 one-sided, 1/2 centred
    threshold: float  #: m/s: the sharp switch's ``Vn`` (the guard times the speed scale)
    surface: bool  #: the free-surface factor applies (its factor is exactly 1 at ``f0 = 1``)
    inverse_surface: float  #: ``1 / D`` (1/m)
    surface_fraction: float  #: ``f0``
    surface_front: bool  #: the reduction applies near the front face
    surface_rear: float  #: m: and near the rear face at this depth (``inf``: not)
    entering: bool  #: the entry factor applies (some point may be outside the target)
    smooth_entry: bool  #: points enter over their own extent (else sharply)


def law_velocity_scalars(normal_velocity: Any, separation: bool) -> Any:
    """The normal velocity (m/s) a point's law is evaluated at: ``max(Vn, 0)`` with separation (the contact factor
    unloads a point moving away, and a user's law is defined for ``Vn >= 0`` only), ``Vn`` itself without (the
    built-in law extended to ``Vn < 0`` as an odd function)."""
    return np.maximum(normal_velocity, 0.0) if separation else normal_velocity


def speed_scale_scalars(speed: float, spin: float, max_radius: float) -> float:
    """``U = |V| + |omega| r_max`` (m/s): no surface point moves faster (``speed``, m/s; ``spin``, rad/s;
    ``max_radius``, m).  It scales the contact ramp's width and the normal-velocity guard."""
    return speed + spin * max_radius


def contact_width_scalars(contact_width: float, contact_incidence: float, speed_scale: float) -> float:
    """``W = w + delta U`` (m/s): the contact ramp's width at the speed scale ``U`` (:func:`speed_scale_scalars`);
    0 with the sharp switch (both zero)."""
    return contact_width + contact_incidence * speed_scale


def switches_scalars(effects: Any, width: float, guard: float, entering: bool, plain: bool, surface: bool) -> Switches:
    """The :class:`Switches` of the effects record ``effects`` (:data:`~fem_loads.kernels.records.EFFECTS`, or an object
    with its fields) at the contact width ``width`` (m/s; 0: sharp, or a body at rest without a fixed width), the
    sharp switch's threshold ``guard`` (m/s) and ``entering``.  ``plain`` (the record's ``plain``): its switches as
    constants, for the compiled loop that passes it as one, with the free-surface factor where ``surface`` (without
    a free surface it is exactly 1)."""
    depth = effects.surface_depth
    return Switches(
        plain or effects.separation,
        plain or effects.smooth_contact,
        1.0 / width if width > 0.0 else 0.0,
        effects.contact_offset,
        guard,
        surface if plain else depth > 0.0,
        1.0 / depth if depth > 0.0 else 0.0,
        effects.surface_fraction if depth > 0.0 else 1.0,
        effects.surface_front,
        effects.surface_rear,
        entering,
        plain or effects.smooth_entry,
    )


def point_stress_scalars(
    stress: Any, normal_velocity: Any, depth: Any, height: Any, inverse_entry: Any, switches: Switches
) -> Any:
    """``f c g e``: a point's law value ``stress`` (Pa) times its contact factor, its free-surface factor at ``depth``
    (m below the free surface) and its entry factor at ``height`` (m above the face it enters through;
    ``inverse_entry`` ``1 / l``, 1/m).  Without separation the law's negative values are cut at 0 instead of the
    contact factor.  ``stress`` may be updated in place (an array the caller owns)."""
    s = switches
    if s.separation:
        stress *= contact_factor_scalars(
            normal_velocity, s.smooth_contact, s.inverse_width, s.contact_offset, s.threshold
        )
    else:
        stress = np.maximum(stress, 0.0)
    if s.surface:
        distance = free_face_distance_scalars(depth, s.surface_front, s.surface_rear)
        stress *= surface_factor_scalars(distance, s.inverse_surface, s.surface_fraction)
    if s.entering:
        stress *= entry_factor_scalars(height, s.smooth_entry, inverse_entry)
    return stress


def in_contact_scalars(normal_velocity: float, switches: Switches) -> bool:
    """Whether a point at ``Vn`` (m/s) has a nonzero contact factor (:func:`contact_factor_scalars`; with
    separation): above the smooth ramp's foot, or above the sharp switch's threshold.  A point's law need not be
    evaluated where it has not."""
    s = switches
    if s.smooth_contact:
        return normal_velocity * s.inverse_width + s.contact_offset > 0.0
    return normal_velocity > s.threshold


def contact_factor_scalars(
    normal_velocity: Any, smooth: bool, inverse_width: float, offset: float, threshold: float
) -> Any:
    """``c(Vn)``: smooth, ``S(Vn / W + offset)`` with ``inverse_width = 1 / W`` (1/(m/s); 0 for a body at rest
    without a fixed width) and ``offset`` 0 (one-sided: from 0 at ``Vn = 0`` to 1 at ``W``) or 1/2 (centred on
    ``Vn = 0``); sharp, 1 where ``Vn > threshold`` (m/s) and 0 elsewhere."""
    if smooth:
        return smooth_step_scalars(add_term(normal_velocity * inverse_width, offset))
    return (normal_velocity > threshold) * 1.0


def entry_factor_scalars(height: Any, smooth: bool, inverse_length: Any) -> Any:
    """``e(H)`` of a point at ``height`` (m) above a face it enters through (the target's front face, or a layer's
    top interface): smooth, ``S(1/2 - H / l)`` with ``inverse_length = 1 / l`` (1/m; ``l`` the point's own
    extent), from 0 at ``l/2`` above to 1 at ``l/2`` below; sharp, 1 below the face and 0 above."""
    if smooth:
        argument = height * inverse_length
        argument *= -1.0
        argument += 0.5  # 1/2 - H / l, in place on an array
        return smooth_step_scalars(argument)
    return (height < 0.0) * 1.0


def layer_share_scalars(top: float, bottom: float, depth: Any, smooth: bool, inverse_length: Any) -> Any:
    """The share of a layer between the interfaces at depths ``top < bottom`` (m; ``-inf`` and ``inf`` where there
    is none) in the stress of a point at ``depth`` (m): ``e(top - d) - e(bottom - d)`` (:func:`entry_factor_scalars`),
    so that a point enters the layer below as it enters the target, and the shares of all layers sum to 1.

    An infinite bound is not evaluated: its factor is exactly 1 (``top = -inf``) or 0 (``bottom = inf``), and a
    pass over the points fewer is what keeps the numpy layered target as fast as one entry factor per interface."""
    if bottom == math.inf:
        if top == -math.inf:
            return 1.0  # the one layer of a target without interfaces
        return entry_factor_scalars(top - depth, smooth, inverse_length)
    below = entry_factor_scalars(bottom - depth, smooth, inverse_length)
    if top == -math.inf:
        return 1.0 - below
    return entry_factor_scalars(top - depth, smooth, inverse_length) - below


def surface_factor_scalars(depth: Any, inverse_depth: float, surface_fraction: float) -> Any:
    """``g(z) = f0 + (1 - f0) S(z / D)`` of a point at ``depth`` ``z`` (m below the free surface), with
    ``inverse_depth = 1 / D`` (1/m) and ``surface_fraction`` ``f0``: ``f0`` at and above the surface, 1 from
    ``D`` down.  ``f0 = 1`` is no reduction, exactly."""
    factor = smooth_step_scalars(depth * inverse_depth)
    factor *= 1.0 - surface_fraction
    factor += surface_fraction
    return factor


def free_face_distance_scalars(depth: Any, front: bool, rear: float) -> Any:
    """The distance (m) of a point at ``depth`` (m below the front face) into the target from the nearest free face
    the reduction applies at: the front face (``front``) and a rear face at depth ``rear`` (``inf``: none)."""
    if rear == math.inf:
        return depth  # the front face alone (a reduction without a face is refused before)
    if front:
        return np.minimum(depth, rear - depth)
    return rear - depth


def friction_stress_scalars(stress: Any, coefficient: float, cap: float) -> Any:
    """``tau = mu sigma`` (Coulomb, ``coefficient`` ``mu``), or ``min(mu sigma, cap)`` for a ``cap > 0`` (the same
    units as ``stress``: Pa, or Pa m^2 for a stress times its weight); 0: no cap."""
    tau = coefficient * stress
    if cap > 0.0:
        return np.minimum(tau, cap)
    return tau
