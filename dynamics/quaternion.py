"""Unit quaternions ``q = (w, x, y, z)`` (scalar first) for rigid-body attitude.

``rotation_matrix(q)`` maps body coordinates to world coordinates; attitude kinematics with the body-frame
angular velocity ``omega`` read ``dq/dt = q * (0, omega) / 2``.

The functions, called several times per stage of every step, unpack their 3- and 4-vectors to Python floats
(numpy's per-call overhead is most of the cost at this size).  The arithmetic is in the ``*_scalars``
functions, on floats only, so that the compiled step (:mod:`dynamics.compiled_rk`) compiles the same expressions.
"""

from __future__ import annotations

import math

import numpy as np

__all__ = [
    "multiply",
    "exp_map",
    "compose",
    "rotation_matrix",
    "rotation_matrices",
    "from_rotation_matrix",
    "right_jacobian_inverse",
    "normalize",
    "hamilton_scalars",
    "exp_scalars",
    "rotation_scalars",
    "dexp_inverse_scalars",
]


def hamilton_scalars(
    pw: float, px: float, py: float, pz: float, qw: float, qx: float, qy: float, qz: float
) -> tuple[float, float, float, float]:
    """The Hamilton product ``p * q`` on the components."""
    return (
        pw * qw - px * qx - py * qy - pz * qz,
        pw * qx + px * qw + py * qz - pz * qy,
        pw * qy - px * qz + py * qw + pz * qx,
        pw * qz + px * qy - py * qx + pz * qw,
    )


def multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p * q``."""
    return np.array(hamilton_scalars(*p.tolist(), *q.tolist()))


def exp_scalars(vx: float, vy: float, vz: float) -> tuple[float, float, float, float]:
    """The unit quaternion of the rotation vector ``(vx, vy, vz)``, as components."""
    angle2 = vx * vx + vy * vy + vz * vz
    angle = math.sqrt(angle2)
    half = 0.5 * angle
    # sin(half)/angle, with its series near zero so that the map stays smooth
    scale = math.sin(half) / angle if angle > 1e-8 else 0.5 - angle2 / 48.0
    return math.cos(half), scale * vx, scale * vy, scale * vz


def exp_map(rotation_vector: np.ndarray) -> np.ndarray:
    """Unit quaternion of the rotation by ``|v|`` radians about ``v``."""
    return np.array(exp_scalars(*rotation_vector.tolist()))


def compose(q: np.ndarray, rotation_vector: np.ndarray) -> np.ndarray:
    """``q * exp_map(rotation_vector)`` in one call (the attitude inside a Runge-Kutta step)."""
    qw, qx, qy, qz = q.tolist()
    return np.array(hamilton_scalars(qw, qx, qy, qz, *exp_scalars(*rotation_vector.tolist())))


def normalize(q: np.ndarray) -> np.ndarray:
    """``q / |q|``.

    ``|q|^2`` is summed as ``(w^2 + y^2) + (x^2 + z^2)``: the same bits for the quaternions of mirrored
    attitudes (which swap ``w`` with ``y`` and ``x`` with ``z``, or change signs), which ``q @ q`` (the BLAS
    dot, in an order that depends on the CPU) does not always give.
    """
    w, x, y, z = q.tolist()
    return q / math.sqrt((w * w + y * y) + (x * x + z * z))


def rotation_scalars(w: float, x: float, y: float, z: float) -> tuple[float, ...]:
    """The rotation matrix of a unit quaternion, row by row (nine components)."""
    ww, xx, yy, zz = w * w, x * x, y * y, z * z
    # the homogeneous diagonal, not 1 - 2 (y^2 + z^2): exact zeros for two bitwise-equal components (docs/numerics.md)
    return (
        (ww + xx) - (yy + zz),
        2 * (x * y - w * z),
        2 * (x * z + w * y),
        2 * (x * y + w * z),
        (ww + yy) - (xx + zz),
        2 * (y * z - w * x),
        2 * (x * z - w * y),
        2 * (y * z + w * x),
        (ww + zz) - (xx + yy),
    )


def rotation_matrix(q: np.ndarray) -> np.ndarray:
    """Body-to-world rotation matrix of a unit quaternion."""
    return np.array(rotation_scalars(*q.tolist())).reshape(3, 3)


def rotation_matrices(q: np.ndarray) -> np.ndarray:
    """Body-to-world rotation matrices of unit quaternions ``q``, shape ``(..., 4)``, as shape ``(..., 3, 3)``: each
    :func:`rotation_matrix`'s to the bit (the same arithmetic on arrays)."""
    q = np.asarray(q, dtype=float)
    return np.stack(rotation_scalars(*np.moveaxis(q, -1, 0)), axis=-1).reshape(*q.shape[:-1], 3, 3)


def from_rotation_matrix(matrix: np.ndarray) -> np.ndarray:
    """Unit quaternion (with ``w >= 0``) of a rotation matrix (Shepperd's method)."""
    m = np.asarray(matrix, dtype=float)
    trace = np.trace(m)
    k = int(np.argmax([trace, m[0, 0], m[1, 1], m[2, 2]]))
    if k == 0:
        w = 0.5 * math.sqrt(1.0 + trace)
        q = np.array([w, (m[2, 1] - m[1, 2]) / (4 * w), (m[0, 2] - m[2, 0]) / (4 * w), (m[1, 0] - m[0, 1]) / (4 * w)])
    else:
        i = k - 1
        j, n = (i + 1) % 3, (i + 2) % 3
        r = math.sqrt(1.0 + m[i, i] - m[j, j] - m[n, n])
        q = np.zeros(4)
        q[0] = (m[n, j] - m[j, n]) / (2 * r)
        q[1 + i] = 0.5 * r
        q[1 + j] = (m[j, i] + m[i, j]) / (2 * r)
        q[1 + n] = (m[n, i] + m[i, n]) / (2 * r)
    q = normalize(q)
    return q if q[0] >= 0 else -q


def dexp_inverse_scalars(
    ux: float, uy: float, uz: float, wx: float, wy: float, wz: float
) -> tuple[float, float, float]:
    """:func:`right_jacobian_inverse` on the components of ``u`` and ``omega``."""
    angle2 = ux * ux + uy * uy + uz * uz
    if angle2 < 1e-6:
        c = 1.0 / 12.0 + angle2 / 720.0 + angle2 * angle2 / 30240.0
    else:
        angle = math.sqrt(angle2)
        c = (1.0 - 0.5 * angle / math.tan(0.5 * angle)) / angle2
    ax, ay, az = uy * wz - uz * wy, uz * wx - ux * wz, ux * wy - uy * wx  # u x omega
    bx, by, bz = uy * az - uz * ay, uz * ax - ux * az, ux * ay - uy * ax  # u x (u x omega)
    return wx + 0.5 * ax + c * bx, wy + 0.5 * ay + c * by, wz + 0.5 * az + c * bz


def right_jacobian_inverse(u: np.ndarray, omega: np.ndarray) -> np.ndarray:
    """``du/dt`` for ``q = q0 * exp(u)`` turning with body angular velocity ``omega``: the inverse right Jacobian of
    SO(3), ``omega + u x omega / 2 + c(|u|) u x (u x omega)`` with ``c(t) = (1 - (t/2) cot(t/2)) / t^2``."""
    return np.array(dexp_inverse_scalars(*u.tolist(), *omega.tolist()))
