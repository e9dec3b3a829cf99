"""The DAFL load in compiled code (numba): one loop over the surface points per evaluation.

:func:`dafl_kernel` evaluates the resultant of :meth:`DAFLLoads.__call__ <fem_loads.dafl.DAFLLoads.__call__>`,
every effect included, through the same per-point pipeline (:mod:`fem_loads.kernels.point`).  Mirror images are
kept as the numpy path keeps them (:mod:`fem_loads.images`): each image of the fundamental part's points is summed
with its own signs, in the same order, and the images are folded in mirrored pairs, so a symmetric state gives an
exactly symmetric normal load.

The kernel takes its arrays as one tuple (:func:`kernel_data`), so the compiled Runge-Kutta step
(:mod:`dynamics.compiled_rk`) calls it without knowing what it computes, and a user's law as the address of its
``cfunc`` (:meth:`~fem_loads.user_law.UserLaw.compiled`): the kernel is compiled and cached once for every law.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from ..factors import contact_width_scalars, speed_scale_scalars
from . import layout
from .layout import KERNEL_ARRAYS, kernel_data
from .native import face_frame, point_stress
from .point import (
    Motion,
    blended,
    exposure_correction,
    has_layers,
    has_table,
    image_friction,
    layered_point_stress,
    plain_layer_stresses,
    plain_stress,
    point_law_stress,
    point_motion,
    setup,
)

__all__ = ["dafl_kernel", "lowest_height_kernel", "kernel_data", "KERNEL_ARRAYS"]

# fastmath: reassociation (and fused multiply-adds) let the per-image sums over the points run in SIMD
# lanes; each image runs the same machine code on its own signs, so mirrored images still get
# bitwise-equal sums from bitwise-equal stresses, and the fold stays exact
_FAST = {"reassoc", "contract"}


@njit(cache=True, error_model="numpy", fastmath=_FAST, inline="always")
def _sums(
    data: tuple[np.ndarray, ...],
    motion: Motion,
    sums: np.ndarray,
    friction: np.ndarray,
    plain: bool,
    with_friction: bool,
    layered: bool,
) -> None:
    """Each image's ``sum sigma w [n | r x n]`` into ``sums``; the friction's force and moment (body frame) into
    ``friction``.  ``plain``, ``with_friction`` (:func:`~fem_loads.kernels.point.setup`) and ``layered`` are
    constants in each of the six functions that inline this one, each a loop of its own without the others'
    branches: the plain law with its SIMD lanes (no calls, and no branches that differ from point to point), with
    friction and the free surface or not, and with layers or a strength table (``layered``: read in passes of their
    own) or not; any other one law; and layers."""
    s, (points, normal_arm, point_signs, weights, inverse_entry, depths, stresses) = setup(
        data, motion, plain, with_friction
    )
    g, up, v, w, height = motion.g, motion.up, motion.v, motion.w, motion.height
    with_height, rule, polynomial, switches = s.with_height, s.friction, s.polynomial, s.switches
    vt, wt = (v[0], v[1], v[2]), (w[0], w[1], w[2])
    mu = rule[0]
    layer_stresses = np.empty(weights.shape[0] if plain and layered else 0)
    table_stresses = np.empty(weights.shape[0] if plain and layered and has_table(data) else 0)
    reach = data[layout.DATA_EFFECTS][0].reach
    for k in range(sums.shape[0]):
        gk = (g[k, 0], g[k, 1], g[k, 2], g[k, 3], g[k, 4], g[k, 5])
        upk = (up[k, 0], up[k, 1], up[k, 2])
        sy, sz = point_signs[k, 1], point_signs[k, 2]
        if plain and layered:
            buffers = (layer_stresses, table_stresses)
            plain_layer_stresses(data, normal_arm, points, inverse_entry, gk, upk, height, reach, buffers)
        a0 = a1 = a2 = a3 = a4 = a5 = 0.0
        f0 = f1 = f2 = f3 = f4 = f5 = 0.0
        for j in range(weights.shape[0]):
            n, r, normal_velocity, z = point_motion(normal_arm, points, j, gk, upk, height, with_height)
            weight, inverse = weights[j], inverse_entry[j]
            if plain and layered:
                stress = point_stress(layer_stresses[j], normal_velocity, -z, z, inverse, switches) * weight
            elif plain:
                stress = plain_stress(polynomial, switches, weight, inverse, normal_velocity, z)
            elif layered:
                stress = layered_point_stress(data, s, weight, inverse, normal_velocity, z)
            else:
                stress = point_law_stress(s, depths, stresses, weight, inverse, normal_velocity, z)
            a0 += stress * n[0]
            a1 += stress * n[1]
            a2 += stress * n[2]
            a3 += stress * n[3]
            a4 += stress * n[4]
            a5 += stress * n[5]
            if with_friction and (plain or (mu > 0.0 and stress != 0.0)):
                d0, d1, d2, d3, d4, d5 = image_friction(n, r, sy, sz, weight, rule, vt, wt, normal_velocity, stress)
                f0, f1, f2, f3, f4, f5 = f0 + d0, f1 + d1, f2 + d2, f3 + d3, f4 + d4, f5 + d5
        sums[k, 0], sums[k, 1], sums[k, 2], sums[k, 3], sums[k, 4], sums[k, 5] = a0, a1, a2, a3, a4, a5
        friction[0] += f0
        friction[1] += f1
        friction[2] += f2
        friction[3] += f3
        friction[4] += f4
        friction[5] += f5


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def _plain_sums(data: tuple[np.ndarray, ...], motion: Motion, sums: np.ndarray, friction: np.ndarray) -> None:
    """:func:`_sums` of the plain law without friction or free surface (the shipped scenes' load)."""
    _sums(data, motion, sums, friction, True, False, False)


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def _plain_friction_sums(data: tuple[np.ndarray, ...], motion: Motion, sums: np.ndarray, friction: np.ndarray) -> None:
    """:func:`_sums` of the plain law with friction or a free surface (a coefficient of 0 leaves no friction; without
    a free surface its factor is exactly 1)."""
    _sums(data, motion, sums, friction, True, True, False)


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def _plain_layers_sums(data: tuple[np.ndarray, ...], motion: Motion, sums: np.ndarray, friction: np.ndarray) -> None:
    """:func:`_sums` of layers of plain laws (a slab of concrete, soil over concrete) or of one plain law with a
    strength table, without friction or free surface: the layers' blend and the tables in passes of their own,
    the rest as the plain loop."""
    _sums(data, motion, sums, friction, True, False, True)


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def _plain_layers_friction_sums(
    data: tuple[np.ndarray, ...], motion: Motion, sums: np.ndarray, friction: np.ndarray
) -> None:
    """:func:`_plain_layers_sums` with friction or a free surface."""
    _sums(data, motion, sums, friction, True, True, True)


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def _law_sums(data: tuple[np.ndarray, ...], motion: Motion, sums: np.ndarray, friction: np.ndarray) -> None:
    """:func:`_sums` of every other law and switch, on a target of one law."""
    _sums(data, motion, sums, friction, False, True, False)


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def _layered_sums(data: tuple[np.ndarray, ...], motion: Motion, sums: np.ndarray, friction: np.ndarray) -> None:
    """:func:`_sums` of layers (a slab is one layer over the space behind it)."""
    _sums(data, motion, sums, friction, False, True, True)


@njit(cache=True, error_model="numpy")
def dafl_kernel(
    data: tuple[np.ndarray, ...],
    position: np.ndarray,
    velocity: np.ndarray,
    rotation: np.ndarray,
    angular_velocity: np.ndarray,
    out: np.ndarray,
) -> None:
    """Force (world frame, N) into ``out[:3]`` and moment (body frame, N m) into ``out[3:6]``.

    ``data`` from :func:`kernel_data`; the state as for :class:`~fem_loads.dafl.DAFLLoads`.
    """
    image_signs, point_signs = data[layout.DATA_IMAGE_SIGNS], data[layout.DATA_POINT_SIGNS]
    effects = data[layout.DATA_EFFECTS][0]
    max_radius, reach = effects.max_radius, effects.reach
    for c in range(6):
        out[c] = 0.0
    height, up0, up1, up2 = face_frame(position, rotation, effects.face_normal, effects.face_offset)
    if height - reach >= 0.0:
        return  # wholly outside the target
    images = image_signs.shape[0]
    # each image's generalised velocity (R^T V, omega) and up vector R^T n with its signs: exact sign changes,
    # so an image's Vn and height are the quarter's sums with those signs, in the same order
    g = np.empty((images, 6))
    up = np.empty((images, 3))
    v = np.empty(3)
    for c in range(3):
        v[c] = rotation[0, c] * velocity[0] + rotation[1, c] * velocity[1] + rotation[2, c] * velocity[2]
    for k in range(images):
        for c in range(3):
            g[k, c] = v[c] * image_signs[k, c]
            g[k, 3 + c] = angular_velocity[c] * image_signs[k, 3 + c]
        up[k, 0], up[k, 1], up[k, 2] = up0 * point_signs[k, 0], up1 * point_signs[k, 1], up2 * point_signs[k, 2]
    speed = math.sqrt(velocity[0] * velocity[0] + velocity[1] * velocity[1] + velocity[2] * velocity[2])
    spin = math.sqrt(angular_velocity[0] ** 2 + angular_velocity[1] ** 2 + angular_velocity[2] ** 2)
    speed_scale = speed_scale_scalars(speed, spin, max_radius)
    width = contact_width_scalars(effects.contact_width, effects.contact_incidence, speed_scale)
    embedded = height + reach < 0.0
    motion = Motion(g, up, v, angular_velocity, height, width, effects.guard * speed_scale, embedded)
    sums = np.zeros((images, 6))
    friction = np.zeros(6)
    in_passes = blended(data)
    rubbing = effects.friction > 0.0 or effects.surface_depth > 0.0
    if effects.plain and in_passes and rubbing:
        _plain_layers_friction_sums(data, motion, sums, friction)
    elif effects.plain and in_passes:
        _plain_layers_sums(data, motion, sums, friction)
    elif effects.plain and rubbing:
        _plain_friction_sums(data, motion, sums, friction)
    elif effects.plain:
        _plain_sums(data, motion, sums, friction)
    elif not has_layers(data):
        _law_sums(data, motion, sums, friction)
    else:
        _layered_sums(data, motion, sums, friction)
    if data[layout.DATA_EXPOSURE_COLUMNS].shape[0] > 0:
        exposure_correction(data, motion, effects.plain, sums, friction)
    body = np.empty(6)
    for c in range(6):
        if images == 4:
            # (P0 + Y P1) + Z (P2 + Y P3): mirrored images cancel or add exactly
            y, zs = image_signs[1, c], image_signs[2, c]
            body[c] = -((sums[0, c] + y * sums[1, c]) + zs * (sums[2, c] + y * sums[3, c])) + friction[c]
        elif images == 2:  # one mirror plane: P0 + S P1
            body[c] = -(sums[0, c] + image_signs[1, c] * sums[1, c]) + friction[c]
        else:
            body[c] = -sums[0, c] + friction[c]
    for i in range(3):
        out[i] = rotation[i, 0] * body[0] + rotation[i, 1] * body[1] + rotation[i, 2] * body[2]
        out[3 + i] = body[3 + i]


@njit(cache=True, error_model="numpy")
def lowest_height_kernel(data: tuple[np.ndarray, ...], position: np.ndarray, rotation: np.ndarray) -> float:
    """``min(H - l/2)`` over the points (m, ``H`` the height above the front face): :meth:`DAFLLoads.lowest_height`
    on the kernel's arrays.

    While every point is inside the target (the bounding sphere's top is) it returns that top,
    ``h + r_max``, a negative upper bound: the exit event needs only the sign there, and the heights
    of every point at every step cost as much as a load evaluation.
    """
    points, point_signs = data[layout.DATA_POINTS], data[layout.DATA_POINT_SIGNS]
    half_entry_length, effects = data[layout.DATA_HALF_ENTRY_LENGTH], data[layout.DATA_EFFECTS][0]
    height, up0, up1, up2 = face_frame(position, rotation, effects.face_normal, effects.face_offset)
    top = height + effects.max_radius
    if top < 0.0:
        return top
    lowest = math.inf
    for j in range(points.shape[1]):
        p0, p1, p2 = up0 * points[0, j], up1 * points[1, j], up2 * points[2, j]
        for k in range(point_signs.shape[0]):
            z = height + ((p0 + point_signs[k, 1] * p1) + point_signs[k, 2] * p2) - half_entry_length[j]
            lowest = min(lowest, z)
    return lowest
