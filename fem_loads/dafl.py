"""Differential area force law (DAFL): resultant target loads on a rigid projectile.

For each surface quadrature point with outward normal ``n`` at ``r`` from the
centre of mass, moving with ``u = V + omega x r``:

* ``Vn = u . n`` (positive when the element pushes into the target);
* ``sigma_n = f(Vn)`` when ``Vn > 0`` and the point lies inside the target,
  else 0 (the target separates from surfaces that move away from it);
* ``dF = -sigma_n n dS``, ``F = sum dF``, ``M = sum r x dF``.

The target is the half-space ``Z < 0`` of the world frame (``Z`` up).  All
per-point work is a few matrix-vector products over arrays cached at
construction, so nothing is reassembled per evaluation.
"""

from __future__ import annotations

import math

import numpy as np

from .quadrature import SurfaceQuadrature
from .resistance import ResistanceLaw

__all__ = ["DAFLLoads"]


class DAFLLoads:
    """Resultant force and moment of the DAFL for a rigid-body velocity state.

    Parameters
    ----------
    quadrature : SurfaceQuadrature
        Outer-surface quadrature in the body frame about the centre of mass.
    law : ResistanceLaw
        Normal stress as a function of the normal velocity.
    normal_velocity_guard : float
        Relative guard on ``Vn = 0``: a point carries stress only when
        ``Vn > guard * (|V| + |omega| r_max)``.  The stress jumps from 0 to
        ``A sigma_0`` at ``Vn = 0``; on the shank of a projectile moving
        straight along its axis ``Vn`` is zero up to round-off, and without
        the guard round-off alone would switch on a lateral load of the order
        of ``A sigma_0`` times half the shank area.
    """

    def __init__(self, quadrature: SurfaceQuadrature, law: ResistanceLaw,
                 normal_velocity_guard: float = 1e-9) -> None:
        self.quadrature = quadrature
        self.law = law
        self.normal_velocity_guard = float(normal_velocity_guard)
        q = quadrature
        # [n | r x n]: one product gives Vn = n.V + (r x n).omega, and the
        # weighted stresses times it give force and moment together
        self._normal_arm = np.ascontiguousarray(np.hstack([q.normals, q.moment_arms]))
        self._points = np.ascontiguousarray(q.points)
        self._weights = np.ascontiguousarray(q.weights)
        self._max_radius = float(np.linalg.norm(q.points, axis=1).max())

    def __len__(self) -> int:
        return len(self._weights)

    def heights(self, position: np.ndarray, rotation: np.ndarray) -> np.ndarray:
        """World height ``Z`` (m) of every quadrature point; negative inside the target."""
        return position[2] + self._points @ rotation[2]

    def lowest_height(self, position: np.ndarray, rotation: np.ndarray) -> float:
        """Height of the lowest surface point (m); negative once any point is inside."""
        return float(self.heights(position, rotation).min())

    def stress(self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray,
               angular_velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Normal stress ``sigma_n`` (Pa) and normal velocity ``Vn`` (m/s) at every point.

        Parameters
        ----------
        position : ndarray, shape (3,)
            Centre of mass in the world frame (m).
        velocity : ndarray, shape (3,)
            Centre-of-mass velocity in the world frame (m/s).
        rotation : ndarray, shape (3, 3)
            Body-to-world rotation matrix.
        angular_velocity : ndarray, shape (3,)
            Angular velocity in the body frame (rad/s).
        """
        generalised = np.empty(6)
        generalised[:3] = velocity @ rotation  # R^T V
        generalised[3:] = angular_velocity
        normal_velocity = self._normal_arm @ generalised
        speed = math.sqrt(float(velocity @ velocity))
        spin = math.sqrt(float(angular_velocity @ angular_velocity))
        guard = self.normal_velocity_guard * (speed + spin * self._max_radius)
        loaded = (normal_velocity > guard) & (self.heights(position, rotation) < 0.0)
        sigma = np.where(loaded, self.law.normal_stress(normal_velocity), 0.0)
        return sigma, normal_velocity

    def __call__(self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray,
                 angular_velocity: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Resultant load.

        Returns
        -------
        force : ndarray, shape (3,)
            Force on the projectile in the world frame (N).
        moment : ndarray, shape (3,)
            Moment about the centre of mass in the body frame (N m).
        """
        sigma, _ = self.stress(position, velocity, rotation, angular_velocity)
        load = -(sigma * self._weights) @ self._normal_arm
        return rotation @ load[:3], load[3:]
