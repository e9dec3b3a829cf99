"""Rigid-body state and the Newton-Euler equations of motion."""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Protocol

import numpy as np

from .quaternion import cross, rotation_matrix

__all__ = ["RigidBody", "State", "LoadFunction"]


class LoadFunction(Protocol):
    """Resultant loads on a rigid body.

    Called as ``loads(position, velocity, rotation, angular_velocity)`` with the
    centre-of-mass position and velocity in the world frame (m, m/s), the
    body-to-world rotation matrix and the body-frame angular velocity (rad/s);
    returns the force in the world frame (N) and the moment about the centre
    of mass in the body frame (N m).
    """

    def __call__(self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray,
                 angular_velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]: ...


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

    def accelerations(self, force: np.ndarray, moment: np.ndarray,
                      angular_velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Linear acceleration (world) and angular acceleration (body) from Newton-Euler."""
        gyroscopic = cross(angular_velocity, self.inertia @ angular_velocity)
        return force / self.mass, self._inertia_inverse @ (moment - gyroscopic)

    def kinetic_energy(self, state: State) -> float:
        """Translational plus rotational kinetic energy (J)."""
        w = state.angular_velocity
        return 0.5 * self.mass * float(state.velocity @ state.velocity) + 0.5 * float(w @ self.inertia @ w)


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
        return all(map(math.isfinite, [*self.position.tolist(), *self.velocity.tolist(),
                                       *self.attitude.tolist(), *self.angular_velocity.tolist()]))
