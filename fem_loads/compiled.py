"""The DAFL load in compiled code (numba): one loop over the surface points per evaluation.

:func:`dafl_kernel` evaluates the same resultant as :meth:`DAFLLoads.__call__
<fem_loads.dafl.DAFLLoads.__call__>` for a single resistance law with separation (no
layers, free surface or friction: those stay on the numpy path, :func:`supports`):

* ``Vn = n . (R^T V) + (r x n) . omega`` at every point (its own signs per mirror image);
* ``sigma = (A sigma_0 w + B rho_0 w Vn^2) c(Vn / W) e(Z)`` with the same smooth steps (or the
  sharp switches) and the same bounding-sphere shortcuts;
* ``F = -R sum sigma n``, ``M = -sum sigma r x n``.

Mirror symmetry is kept exactly as on the numpy path (:mod:`fem_loads.images`): each point of the
quarter ``y > 0, z > 0`` is evaluated as its four images, every image's ``Vn`` and height summed
in the same order with its own signs, each image's resultant summed separately over the points,
and the four folded in mirrored pairs.  A state symmetric about a body plane then gives mirrored
images bitwise-equal stresses and sums, and an exactly symmetric load.  A quadrature without
mirror quarters is one "image" of every point.

The kernel takes its arrays as one tuple (:func:`kernel_data`), so the compiled Runge-Kutta step
(:mod:`dynamics.compiled`) can call it without knowing what it computes.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .dafl import DAFLLoads
from .images import IMAGE_SIGNS, POINT_SIGNS
from .resistance import ResistanceLaw

__all__ = ["dafl_kernel", "lowest_height_kernel", "kernel_data", "supports"]

# the constants of kernel_data's last array
(_MAX_RADIUS, _HALF_ENTRY, _CONTACT_WIDTH, _CONTACT_INCIDENCE, _GUARD, _SMOOTH_CONTACT, _SMOOTH_ENTRY, _N_CONSTANTS) = (
    range(8)
)


def supports(loads: DAFLLoads) -> bool:
    """Whether :func:`dafl_kernel` computes ``loads``: one law with separation, no free surface, no friction."""
    return loads._plain


def kernel_data(loads: DAFLLoads) -> tuple[np.ndarray, ...]:
    """The arrays and constants of :func:`dafl_kernel` for ``loads`` (see :func:`supports`).

    ``(normal_arm (6, m), points (3, m), static (m,), dynamic (m,), inverse_entry (m,),
    half_entry_length (m,), image_signs (k, 6), point_signs (k, 3), constants)``: the quarter's
    (or, without mirror quarters, every point's: ``k = 1``) ``[n | r x n]``, points, ``A sigma_0 w``,
    ``B rho_0 w``, ``1 / l`` and ``l / 2``, the images' signs and the scalars.
    """
    if not supports(loads):
        raise ValueError(
            "the compiled load covers one resistance law with separation, without free surface or friction"
        )
    quadrature = loads.quadrature
    if quadrature.mirror_quarters is not None:
        index = quadrature.mirror_quarters[0]
        image_signs, point_signs = IMAGE_SIGNS, POINT_SIGNS
    else:
        index = np.arange(len(loads))
        image_signs, point_signs = np.ones((1, 6)), np.ones((1, 3))
    weights = loads._weights[index]
    entry_length = loads._entry_length[index]
    law = loads.law
    assert isinstance(law, ResistanceLaw)  # supports(): one law
    constants = np.zeros(_N_CONSTANTS)
    constants[_MAX_RADIUS] = loads._max_radius
    constants[_HALF_ENTRY] = loads._half_entry
    constants[_CONTACT_WIDTH] = loads.contact_width
    constants[_CONTACT_INCIDENCE] = loads.contact_incidence
    constants[_GUARD] = loads.normal_velocity_guard
    constants[_SMOOTH_CONTACT] = float(loads._smooth_contact)
    constants[_SMOOTH_ENTRY] = float(loads.entry_smoothing > 0.0)
    inverse_entry = 1.0 / entry_length if loads.entry_smoothing else np.zeros_like(weights)

    def contiguous(array: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(array, dtype=float)

    return (
        contiguous(loads._normal_arm_t[:, index]),
        contiguous(loads._points_t[:, index]),
        contiguous(law.static_stress * weights),
        contiguous(law.dynamic_density * weights),
        contiguous(inverse_entry),
        contiguous(0.5 * entry_length),
        contiguous(image_signs),
        contiguous(point_signs),
        constants,
    )


@njit(cache=True, inline="always")
def _smooth_step(t: float) -> float:
    """``S(clip(t, 0, 1))``, the quintic of :mod:`fem_loads.ramps`, in its operation order."""
    t = min(max(t, 0.0), 1.0)
    t2 = t * t
    return ((((6.0 * t) - 15.0) * t + 10.0) * t2) * t


# fastmath: reassociation (and fused multiply-adds) let the per-image sums over the points run in SIMD
# lanes; each image runs the same machine code on its own signs, so mirrored images still get
# bitwise-equal sums from bitwise-equal stresses, and the fold stays exact
_FAST = {"reassoc", "contract"}


@njit(cache=True, error_model="numpy", fastmath=_FAST)
def _smooth_sums(
    normal_arm: np.ndarray,
    points: np.ndarray,
    static: np.ndarray,
    dynamic: np.ndarray,
    inverse_entry: np.ndarray,
    g: np.ndarray,
    up: np.ndarray,
    height: float,
    inverse_width: float,
    embedded: bool,
    sums: np.ndarray,
) -> None:
    """Each image's ``sum sigma [n | r x n]`` with both smooth ramps (the default load), into ``sums``."""
    for k in range(sums.shape[0]):
        g0, g1, g2, g3, g4, g5 = g[k, 0], g[k, 1], g[k, 2], g[k, 3], g[k, 4], g[k, 5]
        up0, up1, up2 = up[k, 0], up[k, 1], up[k, 2]
        a0 = a1 = a2 = a3 = a4 = a5 = 0.0
        for j in range(static.shape[0]):
            n0, n1, n2 = normal_arm[0, j], normal_arm[1, j], normal_arm[2, j]
            n3, n4, n5 = normal_arm[3, j], normal_arm[4, j], normal_arm[5, j]
            normal_velocity = g0 * n0 + g1 * n1 + g2 * n2 + g3 * n3 + g4 * n4 + g5 * n5
            stress = (normal_velocity * normal_velocity * dynamic[j] + static[j]) * _smooth_step(
                normal_velocity * inverse_width
            )
            if not embedded:
                z = height + (up0 * points[0, j] + up1 * points[1, j] + up2 * points[2, j])
                stress *= _smooth_step(0.5 - z * inverse_entry[j])
            a0 += stress * n0
            a1 += stress * n1
            a2 += stress * n2
            a3 += stress * n3
            a4 += stress * n4
            a5 += stress * n5
        sums[k, 0], sums[k, 1], sums[k, 2], sums[k, 3], sums[k, 4], sums[k, 5] = a0, a1, a2, a3, a4, a5


@njit(cache=True, error_model="numpy")
def _sharp_sums(
    normal_arm: np.ndarray,
    points: np.ndarray,
    static: np.ndarray,
    dynamic: np.ndarray,
    inverse_entry: np.ndarray,
    g: np.ndarray,
    up: np.ndarray,
    height: float,
    inverse_width: float,
    guard: float,
    smooth_contact: bool,
    smooth_entry: bool,
    embedded: bool,
    sums: np.ndarray,
) -> None:
    """:func:`_smooth_sums` with either switch sharp (for comparisons with the paper's law)."""
    for k in range(sums.shape[0]):
        for j in range(static.shape[0]):
            normal_velocity = 0.0
            for c in range(6):
                normal_velocity += g[k, c] * normal_arm[c, j]
            stress = normal_velocity * normal_velocity * dynamic[j] + static[j]
            if smooth_contact:
                stress *= _smooth_step(normal_velocity * inverse_width)
            elif normal_velocity <= guard:
                continue
            if not embedded:
                z = height + (up[k, 0] * points[0, j] + up[k, 1] * points[1, j] + up[k, 2] * points[2, j])
                if smooth_entry:
                    stress *= _smooth_step(0.5 - z * inverse_entry[j])
                elif z >= 0.0:
                    continue
            for c in range(6):
                sums[k, c] += stress * normal_arm[c, j]


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
    normal_arm, points, static, dynamic, inverse_entry, _, image_signs, point_signs, constants = data
    max_radius, half_entry = constants[_MAX_RADIUS], constants[_HALF_ENTRY]
    for c in range(6):
        out[c] = 0.0
    height = position[2]
    if height - max_radius - half_entry >= 0.0:
        return  # wholly above the surface
    embedded = height + max_radius + half_entry < 0.0
    images = image_signs.shape[0]
    # each image's generalised velocity (R^T V, omega) and up vector R[2] with its signs: exact sign changes,
    # so an image's Vn and height are the quarter's sums with those signs, in the same order
    g = np.empty((images, 6))
    up = np.empty((images, 3))
    for k in range(images):
        for c in range(3):
            g[k, c] = (
                rotation[0, c] * velocity[0] + rotation[1, c] * velocity[1] + rotation[2, c] * velocity[2]
            ) * image_signs[k, c]
            g[k, 3 + c] = angular_velocity[c] * image_signs[k, 3 + c]
            up[k, c] = rotation[2, c] * point_signs[k, c]
    speed = math.sqrt(velocity[0] * velocity[0] + velocity[1] * velocity[1] + velocity[2] * velocity[2])
    spin = math.sqrt(angular_velocity[0] ** 2 + angular_velocity[1] ** 2 + angular_velocity[2] ** 2)
    speed_scale = speed + spin * max_radius
    width = constants[_CONTACT_WIDTH] + constants[_CONTACT_INCIDENCE] * speed_scale
    inverse_width = 1.0 / width if width > 0.0 else 0.0
    smooth_contact = constants[_SMOOTH_CONTACT] != 0.0
    smooth_entry = constants[_SMOOTH_ENTRY] != 0.0
    sums = np.zeros((images, 6))
    if smooth_contact and smooth_entry:
        _smooth_sums(normal_arm, points, static, dynamic, inverse_entry, g, up, height, inverse_width, embedded, sums)
    else:
        _sharp_sums(
            normal_arm,
            points,
            static,
            dynamic,
            inverse_entry,
            g,
            up,
            height,
            inverse_width,
            constants[_GUARD] * speed_scale,
            smooth_contact,
            smooth_entry,
            embedded,
            sums,
        )
    body = np.empty(6)
    for c in range(6):
        if images == 4:
            # (P0 + Y P1) + Z (P2 + Y P3): mirrored images cancel or add exactly
            y, zs = image_signs[1, c], image_signs[2, c]
            body[c] = -((sums[0, c] + y * sums[1, c]) + zs * (sums[2, c] + y * sums[3, c]))
        else:
            body[c] = -sums[0, c]
    for i in range(3):
        out[i] = rotation[i, 0] * body[0] + rotation[i, 1] * body[1] + rotation[i, 2] * body[2]
        out[3 + i] = body[3 + i]


@njit(cache=True, error_model="numpy")
def lowest_height_kernel(data: tuple[np.ndarray, ...], position: np.ndarray, up: np.ndarray) -> float:
    """``min(Z - l/2)`` over the points (m): :meth:`DAFLLoads.lowest_height` on the kernel's arrays, for
    ``up = R[2]`` (the world's up direction in the body frame, the last row of the rotation matrix).

    While every point is below the surface (the bounding sphere's top is) it returns that top,
    ``Z_c + r_max``, a negative upper bound: the exit event needs only the sign there, and the heights
    of every point at every step cost as much as a load evaluation.
    """
    points, half_entry_length, point_signs, constants = data[1], data[5], data[7], data[8]
    top = position[2] + constants[_MAX_RADIUS]
    if top < 0.0:
        return top
    up0, up1, up2 = up[0], up[1], up[2]
    lowest = math.inf
    for j in range(points.shape[1]):
        p0, p1, p2 = up0 * points[0, j], up1 * points[1, j], up2 * points[2, j]
        for k in range(point_signs.shape[0]):
            z = position[2] + ((p0 + point_signs[k, 1] * p1) + point_signs[k, 2] * p2) - half_entry_length[j]
            lowest = min(lowest, z)
    return lowest
