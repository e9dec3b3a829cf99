"""Rigid-body state and the Newton-Euler equations of motion."""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from .quaternion import rotation_matrix

__all__ = ["RigidBody", "State", "LoadFunction", "euler_scalars"]


def euler_scalars(
    moment: Sequence[float], angular_velocity: Sequence[float], inertia: Sequence[float], inverse: Sequence[float]
) -> tuple[float, float, float]:
    """Euler's equations: the angular acceleration ``I^-1 (M - omega x (I omega))`` (body frame, rad/s^2) for the
    moment ``M`` (N m), the angular velocity ``omega`` (rad/s), the inertia ``I`` (kg m^2, nine components by rows)
    and its inverse, all floats.  The one definition: the Python step, the compiled step and the pitch-plane model
    use it."""
    m0, m1, m2 = moment
    w0, w1, w2 = angular_velocity
    i00, i01, i02, i10, i11, i12, i20, i21, i22 = inertia
    j00, j01, j02, j10, j11, j12, j20, j21, j22 = inverse
    h0 = i00 * w0 + i01 * w1 + i02 * w2  # I omega
    h1 = i10 * w0 + i11 * w1 + i12 * w2
    h2 = i20 * w0 + i21 * w1 + i22 * w2
    r0 = m0 - (w1 * h2 - w2 * h1)  # M - omega x (I omega)
    r1 = m1 - (w2 * h0 - w0 * h2)
    r2 = m2 - (w0 * h1 - w1 * h0)
    return j00 * r0 + j01 * r1 + j02 * r2, j10 * r0 + j11 * r1 + j12 * r2, j20 * r0 + j21 * r1 + j22 * r2


class LoadFunction(Protocol):
    """Resultant loads on a rigid body.

    Called as ``loads(position, velocity, rotation, angular_velocity)`` with the centre-of-mass position and
    velocity in the world frame (m, m/s), the body-to-world rotation matrix and the body-frame angular velocity
    (rad/s); returns the force in the world frame (N) and the moment about the centre of mass in the body frame
    (N m).
    """

    def __call__(
        self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]: ...


@dataclass(frozen=True)
class RigidBody:
    """Mass and inertia tensor (body frame, about the centre of mass).

    Parameters
    ----------
    mass : float
        Mass (kg).
    inertia : ndarray, shape (3, 3)
        Inertia tensor (kg m^2), symmetric positive definite.
    """

    mass: float
    inertia: np.ndarray
    # derived in __post_init__: both matrices as Python floats (numpy's per-call overhead would dominate on 3-vectors)
    _inertia_rows: tuple[tuple[float, ...], ...] = field(init=False, repr=False, compare=False)
    _inertia_flat: tuple[float, ...] = field(init=False, repr=False, compare=False)
    _inverse_flat: tuple[float, ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        inertia = np.asarray(self.inertia, dtype=float)
        if not (self.mass > 0 and np.isfinite(self.mass)):
            raise ValueError(f"mass = {self.mass}: must be a finite number > 0")
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T, rtol=1e-10, atol=0):
            raise ValueError("inertia: must be a symmetric 3x3 matrix")
        if np.linalg.eigvalsh(inertia).min() <= 0:
            raise ValueError("inertia: must be positive definite")
        object.__setattr__(self, "inertia", inertia)
        object.__setattr__(self, "_inertia_rows", tuple(tuple(row) for row in inertia.tolist()))
        object.__setattr__(self, "_inertia_flat", tuple(inertia.ravel().tolist()))
        object.__setattr__(self, "_inverse_flat", tuple(np.linalg.inv(inertia).ravel().tolist()))

    def accelerations(
        self, force: np.ndarray, moment: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Linear acceleration (world) and angular acceleration (body) from Newton-Euler."""
        alpha = euler_scalars(moment.tolist(), angular_velocity.tolist(), self._inertia_flat, self._inverse_flat)
        return force / self.mass, np.array(alpha)

    def kinetic_energy(self, state: State) -> float:
        """Translational plus rotational kinetic energy (J)."""
        v0, v1, v2 = state.velocity.tolist()
        w0, w1, w2 = state.angular_velocity.tolist()
        rotational = sum(w * (a * w0 + b * w1 + c * w2) for w, (a, b, c) in zip((w0, w1, w2), self._inertia_rows))
        return 0.5 * self.mass * (v0 * v0 + v1 * v1 + v2 * v2) + 0.5 * rotational


@dataclass(frozen=True)
class State:
    """Rigid-body state at time ``time``."""

    time: float  # s
    position: np.ndarray  # shape (3,): the centre of mass, world frame (m)
    velocity: np.ndarray  # shape (3,): velocity of the centre of mass, world frame (m/s)
    attitude: np.ndarray  # shape (4,): unit quaternion, body to world
    angular_velocity: np.ndarray  # shape (3,): body frame (rad/s)
    path_length: float = 0.0  # distance travelled by the centre of mass since the start (m)

    @property
    def rotation(self) -> np.ndarray:
        """Body-to-world rotation matrix."""
        return rotation_matrix(self.attitude)

    @property
    def speed(self) -> float:
        return float(np.sqrt(self.velocity @ self.velocity))

    def is_finite(self) -> bool:
        arrays = (self.position, self.velocity, self.attitude, self.angular_velocity)
        return all(math.isfinite(value) for array in arrays for value in array.tolist())
