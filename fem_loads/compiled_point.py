"""One surface point of the compiled DAFL kernel (:mod:`fem_loads.compiled`): its stress, its friction, and the
correction of the sums for the points the target cannot reach (:mod:`fem_loads.exposure`).

Everything here is inlined into the kernel's loops (``inline="always"``), so that the sums over the points
and the correction of the hidden ones compute each point's stress with the same machine code.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
from numba import njit

from .factors import Switches
from .kernel_layout import (
    DATA_EFFECTS,
    DATA_EXPOSURE_COLUMNS,
    DATA_EXPOSURE_CORNERS,
    DATA_EXPOSURE_FINE,
    DATA_EXPOSURE_ROWS,
    DATA_EXPOSURE_START,
    DATA_INTERFACES,
    DATA_INVERSE_ENTRY,
    DATA_LAWS,
    DATA_NORMAL_ARM,
    DATA_POINT_SIGNS,
    DATA_POINTS,
    DATA_TABLES,
    DATA_WEIGHTS,
)
from .native import cell_exposure, cube_cell, entry_factor, friction_stress, law_stress, point_stress, slip_factor

__all__ = [
    "layered_stress",
    "point_friction",
    "image_friction",
    "law_setup",
    "point_motion",
    "point_law_stress",
    "exposure_correction",
]


@njit(cache=True, error_model="numpy")
def layered_stress(
    data: tuple[np.ndarray, ...], normal_velocity: float, depth: float, smooth: bool, inverse_length: float
) -> float:
    """The layers' laws blended across each interface (:class:`~fem_loads.target.LayeredTarget`), at ``Vn`` (m/s)
    and depth (m): a point enters the layer below as it enters the target (``smooth``, over the length
    ``1 / inverse_length``, m), by the same entry factor."""
    interfaces, laws, tables = data[DATA_INTERFACES], data[DATA_LAWS], data[DATA_TABLES]
    address = data[DATA_EFFECTS][0].user_law
    stress = 0.0
    above = 1.0  # the share of this layer and those below it: the entry factor at its top interface d
    for layer in range(interfaces.shape[0] + 1):
        below = 0.0
        if layer < interfaces.shape[0]:
            below = entry_factor(interfaces[layer] - depth, smooth, inverse_length)
        share = above - below
        if share != 0.0:
            law = laws[layer]
            first, count = law.table_first, law.table_count
            depths, stresses = tables[0, first : first + count], tables[1, first : first + count]
            stress += share * law_stress(law, address, normal_velocity, depth, depths, stresses)
        above = below
        if above == 0.0:
            break
    return stress


@njit(cache=True, inline="always", error_model="numpy")
def point_friction(
    r0: float,
    r1: float,
    r2: float,
    m0: float,
    m1: float,
    m2: float,
    v: np.ndarray,
    w: np.ndarray,
    normal_velocity: float,
    stress: float,
    weight: float,
    mu: float,
    cap: float,
    width: float,
    speed2: float,
) -> tuple[float, float, float, float, float, float]:
    """The friction force and moment (body frame) of one point ``r`` with normal ``m`` carrying ``stress`` (its
    normal stress times its ``weight``): ``-tau k s`` against the slip ``s = u - Vn m``, ``u = v + w x r``."""
    s0 = v[0] + w[1] * r2 - w[2] * r1 - normal_velocity * m0
    s1 = v[1] + w[2] * r0 - w[0] * r2 - normal_velocity * m1
    s2 = v[2] + w[0] * r1 - w[1] * r0 - normal_velocity * m2
    t = friction_stress(stress, mu, cap * weight) * slip_factor(s0 * s0 + s1 * s1 + s2 * s2, width, speed2)
    return -t * s0, -t * s1, -t * s2, -t * (r1 * s2 - r2 * s1), -t * (r2 * s0 - r0 * s2), -t * (r0 * s1 - r1 * s0)


@njit(cache=True, inline="always", error_model="numpy")
def law_setup(
    data: tuple[np.ndarray, ...], width: float, guard: float, embedded: bool
) -> tuple[bool, int, Any, np.ndarray, np.ndarray, Switches]:
    """What every point's stress shares, read once before a loop over the points: ``(layered, address, law, depths,
    stresses, switches)``: the user law's address (0: none), the first layer's law (a :data:`~fem_loads.law_record.LAW`
    record), its strength table, and the factors' :class:`~fem_loads.factors.Switches` at the contact width ``W``
    (m/s) and the sharp switch's ``guard`` (m/s)."""
    effects, law = data[DATA_EFFECTS][0], data[DATA_LAWS][0]
    first, count = law.table_first, law.table_count
    surface_depth = effects.surface_depth
    switches = Switches(
        effects.separation,
        effects.smooth_contact,
        1.0 / width if width > 0.0 else 0.0,
        effects.contact_offset,
        guard,
        surface_depth > 0.0,
        1.0 / surface_depth if surface_depth > 0.0 else 0.0,
        effects.surface_fraction,
        not embedded,
        effects.smooth_entry,
    )
    return (
        data[DATA_INTERFACES].shape[0] > 0,
        effects.user_law,
        law,
        data[DATA_TABLES][0, first : first + count].copy(),
        data[DATA_TABLES][1, first : first + count].copy(),
        switches,
    )


@njit(cache=True, inline="always", error_model="numpy")
def point_setup(
    data: tuple[np.ndarray, ...], width: float, v: np.ndarray
) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, bool, tuple[float, float, float, float]]:
    """What every loop over the points reads from ``data`` before it starts: ``(points, normal_arm, point_signs,
    weights, inverse_entry, needs_depth, rule)``, with ``needs_depth`` whether the stress needs
    each point's depth and ``rule`` the friction's ``(mu, cap, W, |v|^2)`` for :func:`image_friction` (``v``: the
    body's velocity, body frame; ``W``: the contact width, m/s).  The general law's own share is
    :func:`law_setup`."""
    effects = data[DATA_EFFECTS][0]
    needs_depth = effects.needs_depth or effects.surface_depth > 0.0
    speed2 = v[0] * v[0] + v[1] * v[1] + v[2] * v[2]
    rule = (effects.friction, effects.friction_cap, width, speed2)
    return (
        data[DATA_POINTS],
        data[DATA_NORMAL_ARM],
        data[DATA_POINT_SIGNS],
        data[DATA_WEIGHTS],
        data[DATA_INVERSE_ENTRY],
        needs_depth,
        rule,
    )


@njit(cache=True, inline="always", error_model="numpy")
def point_law_stress(
    data: tuple[np.ndarray, ...],
    j: int,
    normal_velocity: float,
    z: float,
    layered: bool,
    address: int,
    law: Any,
    depths: np.ndarray,
    stresses: np.ndarray,
    switches: Switches,
    weights: np.ndarray,
    inverse_entry: np.ndarray,
) -> float:
    """The normal stress of point ``j`` times its weight (Pa m^2) at ``Vn`` (m/s) and height ``z`` (m): its law (one,
    or the layers blended) through :func:`~fem_loads.factors.point_stress_scalars`, as the numpy path has it."""
    # without separation the law's odd extension to Vn < 0 (cut at 0 by the pipeline)
    law_velocity = max(normal_velocity, 0.0) if switches.separation else normal_velocity
    if layered:
        stress = layered_stress(data, law_velocity, -z, switches.smooth_entry, inverse_entry[j])
    else:
        stress = law_stress(law, address, law_velocity, -z, depths, stresses)
    return point_stress(stress, normal_velocity, -z, z, weights[j], inverse_entry[j], switches)


@njit(cache=True, inline="always", error_model="numpy")
def point_motion(
    normal_arm: np.ndarray,
    points: np.ndarray,
    g: np.ndarray,
    up: np.ndarray,
    k: int,
    j: int,
    height: float,
    with_height: bool,
) -> tuple[float, float, float, float, float, float, float, float]:
    """Point ``j`` in image ``k``: the part's ``[n | r x n]`` (6 numbers), ``Vn`` (m/s) from the image's generalised
    velocity ``g[k]``, and the height ``z`` (m; 0 unless ``with_height``) from its up vector ``up[k]``."""
    n0, n1, n2 = normal_arm[0, j], normal_arm[1, j], normal_arm[2, j]
    n3, n4, n5 = normal_arm[3, j], normal_arm[4, j], normal_arm[5, j]
    normal_velocity = g[k, 0] * n0 + g[k, 1] * n1 + g[k, 2] * n2 + g[k, 3] * n3 + g[k, 4] * n4 + g[k, 5] * n5
    z = 0.0  # the height; the depth below the surface is -z
    if with_height:
        z = height + (up[k, 0] * points[0, j] + up[k, 1] * points[1, j] + up[k, 2] * points[2, j])
    return n0, n1, n2, n3, n4, n5, normal_velocity, z


@njit(cache=True, inline="always", error_model="numpy")
def image_friction(
    points: np.ndarray,
    point_signs: np.ndarray,
    k: int,
    j: int,
    normal_arm: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    normal_velocity: float,
    stress: float,
    weight: float,
    friction: tuple[float, float, float, float],
) -> tuple[float, float, float, float, float, float]:
    """:func:`point_friction` of point ``j`` in image ``k`` (its point and normal in the body frame by the image's
    signs); ``friction``: ``(mu, cap, W, |v|^2)``."""
    sy, sz = point_signs[k, 1], point_signs[k, 2]
    r0, r1, r2 = points[0, j], sy * points[1, j], sz * points[2, j]
    m0, m1, m2 = normal_arm[0, j], sy * normal_arm[1, j], sz * normal_arm[2, j]
    mu, cap, width, speed2 = friction
    return point_friction(r0, r1, r2, m0, m1, m2, v, w, normal_velocity, stress, weight, mu, cap, width, speed2)


#: where the smooth contact ramp's argument is below this, its factor (10 t^3) is below 1e-14: a point grazing
#: the soil to round-off (a fin's face in straight motion) is not corrected, at a cost below 1e-17 of the load
_RAMP_FLOOR = 1e-5


@njit(cache=True, error_model="numpy")
def exposure_correction(
    data: tuple[np.ndarray, ...],
    g: np.ndarray,
    up: np.ndarray,
    v: np.ndarray,
    w: np.ndarray,
    height: float,
    width: float,
    guard: float,
    embedded: bool,
    sums: np.ndarray,
    friction: np.ndarray,
) -> None:
    """Add ``(e - 1)`` times the stress sums and friction of each point hidden in the body's direction of motion to
    ``sums`` and ``friction``, which hold every point's at ``e = 1`` (so the loops over all the points keep their
    SIMD lanes).

    The direction is the body's velocity ``v`` (body frame), in each image's own signs; the points to correct are
    those hidden at a corner of its cell of the cube map, or inside a refined one (:attr:`Exposure.cell_rows`), each
    with ``e`` from :func:`~fem_loads.exposure.cell_exposure_scalars`, as the numpy path has it.
    """
    columns, start = data[DATA_EXPOSURE_COLUMNS], data[DATA_EXPOSURE_START]
    rows, masks, fine = data[DATA_EXPOSURE_ROWS], data[DATA_EXPOSURE_CORNERS], data[DATA_EXPOSURE_FINE]
    if v[0] == 0.0 and v[1] == 0.0 and v[2] == 0.0:
        return  # no direction of motion, no shadow
    n = round(math.sqrt((start.shape[0] - 1) / 6.0))  # 6 N^2 cells
    points, normal_arm, point_signs, weights, inverse_entry, needs_depth, rule = point_setup(data, width, v)
    layered, address, law, depths, stresses, switches = law_setup(data, width, guard, embedded)
    mu = rule[0]
    separation, smooth_contact = switches.separation, switches.smooth_contact
    inverse_width, offset = switches.inverse_width, switches.contact_offset
    # the smooth ramp is zero at and below -offset W; the sharp switch at and below the guard
    limit = -math.inf if smooth_contact else guard
    if not smooth_contact:
        inverse_width, offset = 0.0, 1.0
    for k in range(sums.shape[0]):
        sy, sz = point_signs[k, 1], point_signs[k, 2]
        face, i, j, fx, fy = cube_cell(n, v[0], sy * v[1], sz * v[2])  # the direction in the part's frame
        cell = (face * n + i) * n + j
        for entry in range(start[cell], start[cell + 1]):
            row = rows[entry]
            exposure = cell_exposure(masks[entry], fine[entry], fx, fy)
            if exposure == 1.0:
                continue  # exposed here (inside a refined cell hidden elsewhere)
            p = columns[row]
            n0, n1, n2, n3, n4, n5, normal_velocity, z = point_motion(
                normal_arm, points, g, up, k, p, height, needs_depth or not embedded
            )
            if separation and (normal_velocity * inverse_width + offset <= _RAMP_FLOOR or normal_velocity <= limit):
                continue  # below the contact ramp (or where it is below 1e-14), or the sharp switch: nothing to hide
            stress = point_law_stress(
                data, p, normal_velocity, z, layered, address, law, depths, stresses, switches, weights, inverse_entry
            )
            if stress == 0.0:
                continue
            change = (exposure - 1.0) * stress
            sums[k, 0] += change * n0
            sums[k, 1] += change * n1
            sums[k, 2] += change * n2
            sums[k, 3] += change * n3
            sums[k, 4] += change * n4
            sums[k, 5] += change * n5
            if mu > 0.0:
                # the friction at the exposed stress less that at the full one (a cap makes it nonlinear)
                full = image_friction(
                    points, point_signs, k, p, normal_arm, v, w, normal_velocity, stress, weights[p], rule
                )
                part = image_friction(
                    points, point_signs, k, p, normal_arm, v, w, normal_velocity, exposure * stress, weights[p], rule
                )
                for c in range(6):
                    friction[c] += part[c] - full[c]
