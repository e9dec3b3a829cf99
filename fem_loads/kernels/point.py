"""One surface point of the compiled DAFL kernel (:mod:`fem_loads.kernels.mesh_loop`): its motion, its stress, its
friction, and the correction of the sums for the points the target cannot reach (:mod:`fem_loads.exposure`).

Everything here is inlined into the kernel's loops (``inline="always"``), so that the sums over the points
and the correction of the hidden ones compute each point's stress with the same machine code.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from ..factors import Switches, law_velocity_scalars
from . import layout
from .native import (
    Coefficients,
    Parameters,
    cell_exposure,
    cube_cell,
    friction_stress,
    in_contact,
    law_stress,
    law_value,
    law_values,
    layer_share,
    point_stress,
    polynomial_stress,
    power_term,
    slip,
    slip_factor,
    switches,
)

__all__ = [
    "Motion",
    "Setup",
    "setup",
    "point_motion",
    "plain_stress",
    "plain_layer_stresses",
    "table_stresses",
    "point_law_stress",
    "layered_point_stress",
    "image_friction",
    "exposure_correction",
]


class Motion(NamedTuple):
    """The body's state as every loop over the points takes it (the kernel computes it once per evaluation)."""

    g: np.ndarray  #: (k, 6): each image's generalised velocity ``(R^T V, omega)`` with its signs
    up: np.ndarray  #: (k, 3): each image's face normal in the body frame, ``R^T n`` with its signs
    v: np.ndarray  #: (3,): the velocity in the body frame (m/s)
    w: np.ndarray  #: (3,): the angular velocity (rad/s, body frame)
    height: float  #: m: the centre of mass's height above the front face
    width: float  #: m/s: the contact width ``W`` (0: sharp)
    guard: float  #: m/s: the sharp switch's threshold
    embedded: bool  #: every point is wholly inside as far as depth goes (no entry factor)


class Setup(NamedTuple):
    """What every point of a loop shares besides the arrays (:func:`setup`): scalars, tuples and the law's record
    only, so that reading a field inside the loop costs no reference counting."""

    with_height: bool  #: the stress needs each point's height (a depth-dependent law, the free surface, entering)
    friction: tuple[float, float, float, float]  #: ``(mu, cap, W, |v|^2)`` for :func:`image_friction`
    address: int  #: the user law's cfunc (0: the built-in law)
    coefficients: Coefficients  #: the first layer's law (:func:`~fem_loads.kernels.native.law_values`)
    parameters: Parameters  #: and its user law's parameters
    polynomial: tuple[float, float, float, float]  #: its ``(c0, k, c1, c2)``, the plain law's
    switches: Switches


@njit(cache=True, inline="always", error_model="numpy")
def has_layers(data: tuple[np.ndarray, ...]) -> bool:
    """The target has layers (an interface: a slab is one layer over the space behind it)."""
    return data[layout.DATA_INTERFACES].shape[0] > 0


@njit(cache=True, inline="always", error_model="numpy")
def has_table(data: tuple[np.ndarray, ...]) -> bool:
    """Some law of the target has a strength table."""
    return data[layout.DATA_TABLES].shape[1] > 0


@njit(cache=True, inline="always", error_model="numpy")
def has_power(data: tuple[np.ndarray, ...]) -> bool:
    """Some law of the target has a power term (``c`` not 0)."""
    laws = data[layout.DATA_LAWS]
    for layer in range(laws.shape[0]):  # noqa: SIM110 (numba compiles no generator inside any())
        if laws[layer].c != 0.0:
            return True
    return False


@njit(cache=True, inline="always", error_model="numpy")
def blended(data: tuple[np.ndarray, ...]) -> bool:
    """Layers, a strength table or a power term: what the plain loops read in passes of their own
    (:func:`plain_layer_stresses`), outside their SIMD lanes."""
    return has_layers(data) or has_table(data) or has_power(data)


@njit(cache=True, inline="always", error_model="numpy")
def setup(
    data: tuple[np.ndarray, ...], motion: Motion, plain: bool, with_friction: bool
) -> tuple[Setup, tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]]:
    """What a loop over the points reads from the kernel's data once before it starts: its :class:`Setup`, and the
    arrays ``(points, normal_arm, point_signs, weights, inverse_entry, depths, stresses)`` (``depths``,
    ``stresses``: the first layer's strength table), to unpack into the loop's own variables (an array read from a
    tuple per point costs its reference counting, more than the law itself).

    ``plain``: the law is the polynomial of the shipped scenes with both smooth ramps and separation
    (:data:`~fem_loads.kernels.records.EFFECTS`'s ``plain``), and ``with_friction`` whether the loop adds friction or a
    free surface; both constants in the loop that passes them, so that its switches are constants too and the loop
    keeps no branch that differs from point to point."""
    effects, law = data[layout.DATA_EFFECTS][0], data[layout.DATA_LAWS][0]
    first, count, width = law.table_first, law.table_count, motion.width
    v = motion.v
    coefficients, parameters = law_values(law)
    shared = Setup(
        effects.needs_depth or effects.surface_depth > 0.0 or not motion.embedded,
        (effects.friction, effects.friction_cap, width, v[0] * v[0] + v[1] * v[1] + v[2] * v[2]),
        effects.user_law,
        coefficients,
        parameters,
        (coefficients[0], coefficients[1], coefficients[2], coefficients[3]),
        switches(effects, width, motion.guard, not motion.embedded, plain, with_friction),
    )
    arrays = (
        data[layout.DATA_POINTS],
        data[layout.DATA_NORMAL_ARM],
        data[layout.DATA_POINT_SIGNS],
        data[layout.DATA_WEIGHTS],
        data[layout.DATA_INVERSE_ENTRY],
        data[layout.DATA_TABLES][0, first : first + count].copy(),
        data[layout.DATA_TABLES][1, first : first + count].copy(),
    )
    return shared, arrays


@njit(cache=True, inline="always", error_model="numpy")
def point_motion(
    normal_arm: np.ndarray,
    points: np.ndarray,
    j: int,
    g: tuple[float, ...],
    up: tuple[float, float, float],
    height: float,
    with_height: bool,
) -> tuple[tuple[float, ...], tuple[float, float, float], float, float]:
    """Point ``j`` in one image: the part's ``[n | r x n]`` (6 numbers) and point ``r`` (m), ``Vn`` (m/s) from the
    image's generalised velocity ``g``, and the height ``z`` above the front face (m; 0 unless ``with_height``)
    from its ``up``.  The loops read the arrays here and pass on the numbers: an array passed to an inlined
    function per point costs its reference counting, several times the point's arithmetic."""
    n = (normal_arm[0, j], normal_arm[1, j], normal_arm[2, j], normal_arm[3, j], normal_arm[4, j], normal_arm[5, j])
    r = (points[0, j], points[1, j], points[2, j])
    normal_velocity = g[0] * n[0] + g[1] * n[1] + g[2] * n[2] + g[3] * n[3] + g[4] * n[4] + g[5] * n[5]
    z = 0.0  # the height; the depth below the face is -z
    if with_height:
        z = height + (up[0] * r[0] + up[1] * r[1] + up[2] * r[2])
    return n, r, normal_velocity, z


@njit(cache=True, inline="always", error_model="numpy")
def layered_stress(
    data: tuple[np.ndarray, ...], normal_velocity: float, depth: float, smooth: bool, inverse_length: float
) -> float:
    """The layers' laws blended across each interface (:class:`~fem_loads.target.LayeredTarget`), at ``Vn`` (m/s)
    and depth (m): a point enters the layer below as it enters the target (``smooth``, over the length
    ``1 / inverse_length``, m), by the same entry factor."""
    interfaces, laws, tables = data[layout.DATA_INTERFACES], data[layout.DATA_LAWS], data[layout.DATA_TABLES]
    address = data[layout.DATA_EFFECTS][0].user_law
    last = interfaces.shape[0]
    stress = 0.0
    for layer in range(last + 1):
        top = interfaces[layer - 1] if layer > 0 else -math.inf
        bottom = interfaces[layer] if layer < last else math.inf
        share = layer_share(top, bottom, depth, smooth, inverse_length)
        if share != 0.0:
            law = laws[layer]
            first, count = law.table_first, law.table_count
            depths, stresses = tables[0, first : first + count], tables[1, first : first + count]
            stress += share * law_stress(law, address, normal_velocity, depth, depths, stresses)
    return stress


@njit(cache=True, inline="always", error_model="numpy")
def table_stresses(
    table: np.ndarray,
    points: np.ndarray,
    up: tuple[float, float, float],
    height: float,
    depths_reached: tuple[float, float],
    buffer: np.ndarray,
) -> None:
    """Each point's strength-table stress (Pa) into ``buffer``, in SIMD lanes: ``np.interp`` of the depth as the
    sum of the table's segments, each clipped to its own depths, ``s_0 + sum_m slope_m (clip(d, d_m, d_m+1) - d_m)``
    (the same piecewise-linear function, the first and last rows' values beyond them).  A segment wholly above
    the shallowest depth the body reaches adds its whole rise to every point, one wholly below adds nothing: a
    pass over the points only for the segments the body spans (``depths_reached``, m; ``table``: depths and
    stresses, shape (2, rows))."""
    shallowest, deepest = depths_reached
    base = table[1, 0]
    for m in range(table.shape[1] - 1):
        if table[0, m + 1] <= shallowest:
            base += table[1, m + 1] - table[1, m]
    buffer[:] = base
    for m in range(table.shape[1] - 1):
        low, high = table[0, m], table[0, m + 1]
        if high <= shallowest or low >= deepest:
            continue
        slope = (table[1, m + 1] - table[1, m]) / (high - low)
        for j in range(buffer.shape[0]):
            depth = -(height + (up[0] * points[0, j] + up[1] * points[1, j] + up[2] * points[2, j]))
            buffer[j] += slope * (min(max(depth, low), high) - low)


@njit(cache=True, inline="always", error_model="numpy")
def plain_layer_stresses(
    data: tuple[np.ndarray, ...],
    normal_arm: np.ndarray,
    points: np.ndarray,
    inverse_entry: np.ndarray,
    g: tuple[float, ...],
    up: tuple[float, float, float],
    height: float,
    reach: float,
    buffers: tuple[np.ndarray, np.ndarray],
) -> None:
    """Each point's law stress (Pa) on layers of plain laws into ``buffers[0]``: the layers' polynomials, power terms
    and strength tables at ``max(Vn, 0)`` blended across each interface as :func:`layered_stress` blends them, in one
    pass over the points per layer that the body reaches (its centre's ``height`` above the front face give or take
    ``reach``, m), and a table's in passes of their own into ``buffers[1]`` (:func:`table_stresses`), so that each
    pass keeps the SIMD lanes of the plain loop (a power term's pass calls ``pow`` point by point, the main loop
    keeps its lanes).  One law is one layer.  An infinite interface above the first layer and below the last gives
    their blend factors exactly 1 and 0 without a branch."""
    interfaces, laws, tables = data[layout.DATA_INTERFACES], data[layout.DATA_LAWS], data[layout.DATA_TABLES]
    buffer, table_buffer = buffers
    last = interfaces.shape[0]
    shallowest, deepest = -height - reach, -height + reach
    buffer[:] = 0.0
    for layer in range(last + 1):
        top = interfaces[layer - 1] if layer > 0 else -math.inf
        bottom = interfaces[layer] if layer < last else math.inf
        if deepest < top or shallowest > bottom:
            continue  # every point's share of this layer is exactly zero
        law = laws[layer]
        coefficients = law_values(law)[0]
        with_table = law.table_count > 0
        if with_table:
            table = tables[:, law.table_first : law.table_first + law.table_count]
            table_stresses(table, points, up, height, (shallowest, deepest), table_buffer)
        bounds = (top, bottom)
        # one loop with pow and one without, so that a law without a power term keeps its SIMD lanes
        if coefficients[4] != 0.0:
            _layer_pass(
                normal_arm, points, inverse_entry, g, up, height, bounds, coefficients, True, with_table, buffers
            )
        else:
            _layer_pass(
                normal_arm, points, inverse_entry, g, up, height, bounds, coefficients, False, with_table, buffers
            )


@njit(cache=True, inline="always", error_model="numpy")
def _layer_pass(
    normal_arm: np.ndarray,
    points: np.ndarray,
    inverse_entry: np.ndarray,
    g: tuple[float, ...],
    up: tuple[float, float, float],
    height: float,
    bounds: tuple[float, float],
    coefficients: Coefficients,
    with_power: bool,
    with_table: bool,
    buffers: tuple[np.ndarray, np.ndarray],
) -> None:
    """One layer's share of each point's stress added to ``buffers[0]`` (:func:`plain_layer_stresses`): its law at
    ``max(Vn, 0)`` in the order :func:`~fem_loads.resistance.normal_stress_scalars` sums it, between the interfaces
    ``bounds`` (m below the front face); ``with_power`` a constant where it is inlined."""
    buffer, table_buffer = buffers
    top, bottom = bounds
    c0, k, c1, c2, c, n = coefficients
    for j in range(buffer.shape[0]):
        _, _, normal_velocity, z = point_motion(normal_arm, points, j, g, up, height, True)
        share = layer_share(top, bottom, -z, True, inverse_entry[j])
        law_velocity = law_velocity_scalars(normal_velocity, True)
        stress = polynomial_stress(law_velocity, -z, c0, k, c1, c2)
        if with_power:
            stress += power_term(law_velocity, c, n)
        if with_table:
            stress += table_buffer[j]
        buffer[j] += share * stress


@njit(cache=True, inline="always", error_model="numpy")
def plain_stress(
    polynomial: tuple[float, float, float, float],
    switches: Switches,
    weight: float,
    inverse_entry: float,
    normal_velocity: float,
    z: float,
) -> float:
    """A point's normal stress times its ``weight`` (Pa m^2) under the plain law (:func:`setup`; its ``polynomial``
    ``(c0, k, c1, c2)``) at ``Vn`` (m/s) and height ``z`` (m) through
    :func:`~fem_loads.factors.point_stress_scalars` (``inverse_entry``: ``1 / l``)."""
    c0, k, c1, c2 = polynomial
    stress = polynomial_stress(law_velocity_scalars(normal_velocity, True), -z, c0, k, c1, c2)
    return point_stress(stress, normal_velocity, -z, z, inverse_entry, switches) * weight


@njit(cache=True, inline="always", error_model="numpy")
def point_law_stress(
    s: Setup,
    depths: np.ndarray,
    stresses: np.ndarray,
    weight: float,
    inverse_entry: float,
    normal_velocity: float,
    z: float,
) -> float:
    """:func:`plain_stress` under any one law: the :class:`Setup`'s, with its strength table ``depths``,
    ``stresses``.  A loop calls it only where its law is not plain: a law other than the polynomial keeps the loop
    from its SIMD lanes."""
    if s.switches.separation and not in_contact(normal_velocity, s.switches):
        return 0.0  # the law unevaluated where the contact factor is zero: the separating half of the surface
    # without separation the law's odd extension to Vn < 0 (cut at 0 by the pipeline)
    law_velocity = law_velocity_scalars(normal_velocity, s.switches.separation)
    stress = law_value(s.coefficients, s.parameters, s.address, law_velocity, -z, depths, stresses)
    return point_stress(stress, normal_velocity, -z, z, inverse_entry, s.switches) * weight


@njit(cache=True, inline="always", error_model="numpy")
def layered_point_stress(
    data: tuple[np.ndarray, ...], s: Setup, weight: float, inverse_entry: float, normal_velocity: float, z: float
) -> float:
    """:func:`point_law_stress` of the layers blended (:func:`layered_stress`).  Only the layered loop calls it: its
    ``data`` costs reference counting per point that the one-law loops do without."""
    if s.switches.separation and not in_contact(normal_velocity, s.switches):
        return 0.0
    law_velocity = law_velocity_scalars(normal_velocity, s.switches.separation)
    stress = layered_stress(data, law_velocity, -z, s.switches.smooth_entry, inverse_entry)
    return point_stress(stress, normal_velocity, -z, z, inverse_entry, s.switches) * weight


@njit(cache=True, inline="always", error_model="numpy")
def image_friction(
    n: tuple[float, ...],
    r: tuple[float, float, float],
    sy: float,
    sz: float,
    weight: float,
    rule: tuple[float, float, float, float],
    v: tuple[float, float, float],
    w: tuple[float, float, float],
    normal_velocity: float,
    stress: float,
) -> tuple[float, float, float, float, float, float]:
    """The friction force and moment (body frame) of a point of the part (``[n | r x n]`` and point ``r``, m) in the
    image of signs ``(1, sy, sz)``, carrying ``stress`` (its normal stress times its ``weight``) under the ``rule``
    ``(mu, cap, W, |v|^2)``: ``-tau k s`` against the slip ``s = u - Vn m``, ``u = v + w x r``."""
    r0, r1, r2 = r[0], sy * r[1], sz * r[2]
    mu, cap, width, speed2 = rule
    s0, s1, s2 = slip(v, w, (r0, r1, r2), (n[0], sy * n[1], sz * n[2]), normal_velocity)
    t = friction_stress(stress, mu, cap * weight) * slip_factor(s0 * s0 + s1 * s1 + s2 * s2, width, speed2)
    return -t * s0, -t * s1, -t * s2, -t * (r1 * s2 - r2 * s1), -t * (r2 * s0 - r0 * s2), -t * (r0 * s1 - r1 * s0)


#: where the smooth contact ramp's argument is below this, its factor (10 t^3) is below 1e-14: a point grazing
#: the soil to round-off (a fin's face in straight motion) is not corrected, at a cost below 1e-17 of the load
_RAMP_FLOOR = 1e-5


@njit(cache=True, error_model="numpy")
def exposure_correction(
    data: tuple[np.ndarray, ...], motion: Motion, plain: bool, sums: np.ndarray, friction: np.ndarray
) -> None:
    """Add ``(e - 1)`` times the stress sums and friction of each point hidden in the body's direction of motion to
    ``sums`` and ``friction``, which hold every point's at ``e = 1`` (so the loops over all the points keep their
    SIMD lanes).

    The direction is the body's velocity ``v`` (body frame), in each image's own signs; the points to correct are
    those hidden at a corner of its cell of the cube map, or inside a refined one (:attr:`Exposure.cell_rows`), each
    with ``e`` from :func:`~fem_loads.exposure.cell_exposure_scalars`, as the numpy path has it.
    """
    columns, start = data[layout.DATA_EXPOSURE_COLUMNS], data[layout.DATA_EXPOSURE_START]
    rows, masks = data[layout.DATA_EXPOSURE_ROWS], data[layout.DATA_EXPOSURE_CORNERS]
    fine = data[layout.DATA_EXPOSURE_FINE]
    v, w, g, up = motion.v, motion.w, motion.g, motion.up
    if v[0] == 0.0 and v[1] == 0.0 and v[2] == 0.0:
        return  # no direction of motion, no shadow
    resolution = round(math.sqrt((start.shape[0] - 1) / 6.0))  # 6 N^2 cells
    # the plain law point by point where its loop reads no table; layers through their blend
    layers, plain_point = has_layers(data), plain and not blended(data)
    s, (points, normal_arm, point_signs, weights, inverse_entry, depths, stresses) = setup(data, motion, plain, True)
    switches = s.switches
    vt, wt = (v[0], v[1], v[2]), (w[0], w[1], w[2])
    # the smooth ramp is zero at and below -offset W; the sharp switch at and below the guard
    inverse_width, offset, limit = switches.inverse_width, switches.contact_offset, -math.inf
    if not switches.smooth_contact:
        inverse_width, offset, limit = 0.0, 1.0, motion.guard
    for k in range(sums.shape[0]):
        sy, sz = point_signs[k, 1], point_signs[k, 2]
        face, i, j, fx, fy = cube_cell(resolution, v[0], sy * v[1], sz * v[2])  # the direction in the part's frame
        cell = (face * resolution + i) * resolution + j
        gk = (g[k, 0], g[k, 1], g[k, 2], g[k, 3], g[k, 4], g[k, 5])
        upk = (up[k, 0], up[k, 1], up[k, 2])
        for entry in range(start[cell], start[cell + 1]):
            exposure = cell_exposure(masks[entry], fine[entry], fx, fy)
            if exposure == 1.0:
                continue  # exposed here (inside a refined cell hidden elsewhere)
            p = columns[rows[entry]]
            n, r, normal_velocity, z = point_motion(normal_arm, points, p, gk, upk, motion.height, s.with_height)
            if switches.separation and (
                normal_velocity * inverse_width + offset <= _RAMP_FLOOR or normal_velocity <= limit
            ):
                continue  # below the contact ramp (or where it is below 1e-14), or the sharp switch: nothing to hide
            weight, inverse = weights[p], inverse_entry[p]
            if plain_point:
                stress = plain_stress(s.polynomial, s.switches, weight, inverse, normal_velocity, z)
            elif layers:
                stress = layered_point_stress(data, s, weight, inverse, normal_velocity, z)
            else:
                stress = point_law_stress(s, depths, stresses, weight, inverse, normal_velocity, z)
            if stress == 0.0:
                continue
            change = (exposure - 1.0) * stress
            for c in range(6):
                sums[k, c] += change * n[c]
            if s.friction[0] > 0.0:
                # the friction at the exposed stress less that at the full one (a cap makes it nonlinear)
                full = image_friction(n, r, sy, sz, weight, s.friction, vt, wt, normal_velocity, stress)
                part = image_friction(n, r, sy, sz, weight, s.friction, vt, wt, normal_velocity, exposure * stress)
                for c in range(6):
                    friction[c] += part[c] - full[c]
