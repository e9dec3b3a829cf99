"""Resistance laws of one's own, as a scene names them: ``law = {function = "laws/soil_laws.py:NAME", ...}``.

Each is ``def NAME(normal_velocity, depth, p1, p2, ...)``: the normal stress (Pa) on a surface element that
moves into the target at ``normal_velocity`` (m/s, >= 0 with separation) at ``depth`` (m below the target
surface; slightly negative for an element entering), with the law's parameters after them.  penetrate
calls it on numpy arrays of all elements (the numpy path) and on floats (the compiled kernel, through
numba), so it is written with numpy's functions, which take both.
"""

import numpy as np


def cavity_expansion(normal_velocity, depth, c0, c2):
    """``c0 + c2 Vn^2``: the built-in cavity-expansion law written as a user law (``c0 = A sigma_0`` in Pa,
    ``c2 = B rho_0`` in kg/m^3); the test that a user law runs as the built-in one does."""
    return c0 + c2 * normal_velocity * normal_velocity


def overburden(normal_velocity, depth, c0, c2, unit_weight, lateral_ratio):
    """Cavity expansion whose strength grows with the soil's overburden: ``c0 + K gamma max(z, 0) + c2 Vn^2``
    (``unit_weight`` gamma in N/m^3, ``lateral_ratio`` K the ratio of the horizontal to the vertical stress)."""
    return c0 + lateral_ratio * unit_weight * np.maximum(depth, 0.0) + c2 * normal_velocity * normal_velocity


def rate_hardening(normal_velocity, depth, c0, c2, reference_speed, exponent):
    """A strength that hardens with the rate of loading, ``c0 (1 + (Vn / V_ref)^m) + c2 Vn^2`` (``V_ref`` in
    m/s, ``m`` dimensionless): an example of a law no built-in family holds."""
    return c0 * (1.0 + (normal_velocity / reference_speed) ** exponent) + c2 * normal_velocity * normal_velocity
