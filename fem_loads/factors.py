"""The factors of a surface point's stress, each defined once.

The DAFL stress of a point is its target's law times factors, and its friction stress a function of that:

    sigma = f(Vn, z) c(Vn) g(z) e(H) x,    tau = min(mu sigma, tau_s)

* ``c`` the contact factor (:func:`contact_factor_scalars`): the target separates from surface that moves away
  from it, smoothly over the contact width or at a sharp switch;
* ``g`` the free-surface reduction (:func:`surface_factor_scalars`);
* ``e`` the entry factor (:func:`entry_factor_scalars`): a point enters the target (or a layer below an
  interface) over its own extent ``l``;
* ``x`` the exposure (:func:`fem_loads.exposure.cell_exposure_scalars`);
* ``tau`` the friction stress (:func:`friction_stress_scalars`), along the slip by
  :func:`fem_loads.target.slip_factor_scalars`.

Each is written on floats and numpy arrays alike, with the smooth step of :mod:`fem_loads.ramps`: the numpy
path evaluates it on every point at once, and :mod:`fem_loads.native` compiles the very same function for the
compiled kernels (the mesh's and the rings').  A flag such as ``smooth`` is one value for all the points, so a
compiled loop that passes a constant keeps no branch.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from .ramps import smooth_step_scalars

__all__ = ["contact_factor_scalars", "entry_factor_scalars", "surface_factor_scalars", "friction_stress_scalars"]


def contact_factor_scalars(
    normal_velocity: Any, smooth: bool, inverse_width: float, offset: float, threshold: float
) -> Any:
    """``c(Vn)``: smooth, ``S(Vn / W + offset)`` with ``inverse_width = 1 / W`` (1/(m/s); 0 for a body at rest
    without a fixed width) and ``offset`` 0 (one-sided: from 0 at ``Vn = 0`` to 1 at ``W``) or 1/2 (centred on
    ``Vn = 0``); sharp, 1 where ``Vn > threshold`` (m/s) and 0 elsewhere."""
    if smooth:
        # on an array the augmented operation works in place (one temporary)
        argument = normal_velocity * inverse_width
        argument += offset
        return smooth_step_scalars(argument)
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


def surface_factor_scalars(depth: Any, inverse_depth: float, surface_fraction: float) -> Any:
    """``g(z) = f0 + (1 - f0) S(z / D)`` of a point at ``depth`` ``z`` (m below the free surface), with
    ``inverse_depth = 1 / D`` (1/m) and ``surface_fraction`` ``f0``: ``f0`` at and above the surface, 1 from
    ``D`` down.  ``f0 = 1`` is no reduction, exactly."""
    factor = smooth_step_scalars(depth * inverse_depth)
    factor *= 1.0 - surface_fraction
    factor += surface_fraction
    return factor


def friction_stress_scalars(stress: Any, coefficient: float, cap: float) -> Any:
    """``tau = mu sigma`` (Coulomb, ``coefficient`` ``mu``), or ``min(mu sigma, cap)`` for a ``cap > 0`` (the same
    units as ``stress``: Pa, or Pa m^2 for a stress times its weight); 0: no cap."""
    tau = coefficient * stress
    if cap > 0.0:
        return np.minimum(tau, cap)
    return tau
