"""Rigid-body state and the Newton-Euler equations of motion."""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from .quaternion import rotation_matrix

__all__ = ["RigidBody", "State", "LoadFunction"]


class LoadFunction(Protocol):
    """Resultant loads on a rigid body.

    Called as ``loads(position, velocity, rotation, angular_velocity)`` with the
    centre-of-mass position and velocity in the world frame (m, m/s), the
    body-to-world rotation matrix and the body-frame angular velocity (rad/s);
    returns the force in the world frame (N) and the moment about the centre
    of mass in the body frame (N m).
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
    # derived in __post_init__: the inverse, and both matrices' rows as Python floats
    _inertia_inverse: np.ndarray = field(init=False, repr=False, compare=False)
    _inertia_rows: tuple[tuple[float, ...], ...] = field(init=False, repr=False, compare=False)
    _inverse_rows: tuple[tuple[float, ...], ...] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        inertia = np.asarray(self.inertia, dtype=float)
        if not (self.mass > 0 and np.isfinite(self.mass)):
            raise ValueError(f"mass = {self.mass}: must be a finite number > 0")
        if inertia.shape != (3, 3) or not np.allclose(inertia, inertia.T, rtol=1e-10, atol=0):
            raise ValueError("inertia: must be a symmetric 3x3 matrix")
        if np.linalg.eigvalsh(inertia).min() <= 0:
            raise ValueError("inertia: must be positive definite")
        object.__setattr__(self, "inertia", inertia)
        object.__setattr__(self, "_inertia_inverse", np.linalg.inv(inertia))
        # the same matrices as Python floats: called several times per step on 3-vectors, where
        # numpy's per-call overhead (~1 us) is most of the cost
        object.__setattr__(self, "_inertia_rows", tuple(tuple(row) for row in inertia.tolist()))
        object.__setattr__(self, "_inverse_rows", tuple(tuple(row) for row in self._inertia_inverse.tolist()))

    def accelerations(
        self, force: np.ndarray, moment: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        """Linear acceleration (world) and angular acceleration (body) from Newton-Euler."""
        w0, w1, w2 = angular_velocity.tolist()
        h0, h1, h2 = (a * w0 + b * w1 + c * w2 for a, b, c in self._inertia_rows)  # I omega
        m0, m1, m2 = moment.tolist()
        # M - omega x (I omega)
        r0, r1, r2 = m0 - (w1 * h2 - w2 * h1), m1 - (w2 * h0 - w0 * h2), m2 - (w0 * h1 - w1 * h0)
        return force / self.mass, np.array([a * r0 + b * r1 + c * r2 for a, b, c in self._inverse_rows])

    def kinetic_energy(self, state: State) -> float:
        """Translational plus rotational kinetic energy (J)."""
        v0, v1, v2 = state.velocity.tolist()
        w0, w1, w2 = state.angular_velocity.tolist()
        rotational = sum(w * (a * w0 + b * w1 + c * w2) for w, (a, b, c) in zip((w0, w1, w2), self._inertia_rows))
        return 0.5 * self.mass * (v0 * v0 + v1 * v1 + v2 * v2) + 0.5 * rotational


@dataclass(frozen=True)
class State:
    """Rigid-body state at time ``time``.

    Attributes
    ----------
    time : float
        Time (s).
    position : ndarray, shape (3,)
        Centre of mass, world frame (m).
    velocity : ndarray, shape (3,)
        Centre-of-mass velocity, world frame (m/s).
    attitude : ndarray, shape (4,)
        Unit quaternion, body to world.
    angular_velocity : ndarray, shape (3,)
        Angular velocity, body frame (rad/s).
    path_length : float
        Distance travelled by the centre of mass since the start (m).
    """

    time: float
    position: np.ndarray
    velocity: np.ndarray
    attitude: np.ndarray
    angular_velocity: np.ndarray
    path_length: float = 0.0

    @property
    def rotation(self) -> np.ndarray:
        """Body-to-world rotation matrix."""
        return rotation_matrix(self.attitude)

    @property
    def speed(self) -> float:
        return float(np.sqrt(self.velocity @ self.velocity))

    def is_finite(self) -> bool:
        return all(
            map(
                math.isfinite,
                [
                    *self.position.tolist(),
                    *self.velocity.tolist(),
                    *self.attitude.tolist(),
                    *self.angular_velocity.tolist(),
                ],
            )
        )
