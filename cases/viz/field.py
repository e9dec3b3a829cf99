"""The resistance field on the projectile's surface at any recorded step of a run, and the instants worth showing.

What is drawn
-------------
The loads integrate the normal stress ``sigma_n`` at the surface quadrature
points (for the default ``quadrature_order = 2``, three points per facet of the
outer surface mesh).  A rendering gives every facet the area-weighted mean of
the stress at its own quadrature points,

    sigma_facet = sum_i sigma_i w_i / sum_i w_i,

so ``sum_facets sigma_facet * area_facet`` is exactly the ``sum_i sigma_i w_i``
the load integrates: the picture is the integrated field, spread evenly over
each facet, neither smoothed across facets nor re-evaluated elsewhere.  A facet
cut by the target surface shows the mean over its embedded and free parts.
With friction the tangential stress ``tau`` (its magnitude; it acts against
the local slip) is averaged the same way.  The stresses come from the run's own
load function (:meth:`fem_loads.DAFLLoads.surface_stress`): nothing of the
physics is evaluated here.  Second-order facets are drawn as four flat
triangles through their corner and edge nodes, each with the parent facet's
value.

The quadrature points of facet ``k`` are rows ``k * m .. k * m + m - 1`` of the
:class:`~fem_loads.quadrature.SurfaceQuadrature` (``m`` points per facet, in
the order of the mesh's ``outer`` triangles): that is how scikit-fem's facet
basis lays them out.  :func:`surface_mesh` checks the layout geometrically and
refuses a quadrature that does not follow it.

Frames
------
World frame ``X`` (right in the side views), ``Y`` (into the picture), ``Z``
up; the target is ``Z < 0``.  Body points are carried to the world by the
state's rotation and centre-of-mass position, so every picture and every
ParaView file has the projectile at its true position and attitude.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import pandas as pd

from dynamics.quaternion import rotation_matrix
from fem_loads import DAFLLoads

from ..run import CONVERGENCE_THRESHOLD, PreparedProjectile, RunResult, attack_angle_peak, body_mesh, history_table
from ..scene import InputError, Numerics

__all__ = [
    "SurfaceMesh",
    "surface_mesh",
    "SurfaceField",
    "FieldEvaluator",
    "key_instants",
    "resolve_instants",
    "frame_rows",
    "INSTANT_NAMES",
    "INSTANT_LABELS",
]

INSTANT_NAMES = ("embedded", "peak", "converged", "end")
INSTANT_LABELS = {"embedded": "nose embedded", "peak": "peak attack angle", "converged": "converged", "end": "end"}

# second-order triangle (corners 0-2, edge nodes 3 = 01, 4 = 12, 5 = 02) as four flat ones
_SPLIT6 = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])


@dataclass(frozen=True)
class SurfaceMesh:
    """The outer surface as flat triangles in the body frame, about the centre of mass.

    Attributes
    ----------
    points : ndarray, shape (n_points, 3)
        Vertices (m), body frame (``x`` towards the nose), relative to the centre of mass.
    triangles : ndarray, shape (n_triangles, 3)
        Vertex indices of the drawn triangles (outward orientation).
    facet : ndarray, shape (n_triangles,)
        The mesh facet each drawn triangle belongs to (four per second-order facet).
    n_facets : int
        Number of facets of the outer surface mesh.
    points_per_facet : int
        Quadrature points per facet.
    """

    points: np.ndarray
    triangles: np.ndarray
    facet: np.ndarray
    n_facets: int
    points_per_facet: int


def surface_mesh(prepared: PreparedProjectile, numerics: Numerics) -> SurfaceMesh:
    """The drawn surface of a prepared projectile and the facet of every quadrature point.

    The mesh comes from the mesh cache (the same file the run used).

    Raises
    ------
    ValueError
        If the quadrature does not have the same number of points on every facet, or its
        points do not lie on their facets in facet order (see the module docstring).
    """
    mesh, _ = body_mesh(prepared.geometry, numerics.mesh_size, numerics.geometry_order)
    outer = np.asarray(mesh.outer, dtype=np.int64)
    n_facets = len(outer)
    n_points = len(prepared.quadrature)
    if n_facets == 0 or n_points % n_facets:
        raise ValueError(f"{n_points} quadrature points do not split evenly over {n_facets} facets")
    per = n_points // n_facets
    nodes = np.asarray(mesh.points, dtype=float) - prepared.mass.centre
    # layout check: the quadrature points of facet k lie on (near) facet k
    corners = nodes[outer[:, :3]]
    centroid = corners.mean(axis=1)
    edge = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    mean_point = prepared.quadrature.points.reshape(n_facets, per, 3).mean(axis=1)
    if np.any(np.linalg.norm(mean_point - centroid, axis=1) > 0.5 * edge):
        raise ValueError("the quadrature points are not laid out facet by facet in the order of the mesh")
    if outer.shape[1] == 6:
        triangles = outer[:, _SPLIT6].reshape(-1, 3)
        facet = np.repeat(np.arange(n_facets), len(_SPLIT6))
    else:
        triangles = outer[:, :3]
        facet = np.arange(n_facets)
    used, compact = np.unique(triangles, return_inverse=True)
    return SurfaceMesh(np.ascontiguousarray(nodes[used]), compact.reshape(-1, 3), facet, n_facets, per)


@dataclass(frozen=True)
class SurfaceField:
    """The resistance field on the surface at one recorded step.

    Attributes
    ----------
    index : int
        Row of the trajectory.
    time, speed : float
        s, m/s.
    attack_angle, total_attack_angle : float
        Signed in-plane and unsigned 3-D attack angle (deg).
    tip_depth : float
        Depth of the nose tip below the surface (m).
    position : ndarray, shape (3,)
        Centre of mass, world frame (m).
    velocity : ndarray, shape (3,)
        Centre-of-mass velocity, world frame (m/s).
    rotation : ndarray, shape (3, 3)
        Body-to-world rotation.
    sigma_n : ndarray, shape (n_facets,)
        Area-weighted facet mean of the normal stress (Pa).
    tau : ndarray, shape (n_facets,) or None
        Area-weighted facet mean of the tangential stress magnitude (Pa); None without friction.
    normal_velocity : ndarray, shape (n_facets,)
        Area-weighted facet mean of ``Vn`` (m/s).
    point_sigma_n : ndarray, shape (n_quadrature_points,)
        The normal stress at the quadrature points, as the loads use it (Pa).
    hidden : ndarray of bool, shape (n_facets,)
        The facets the target cannot reach though they advance into it (``Vn > 0``): hidden by the body
        ahead (:mod:`fem_loads.exposure`), on more than half their area.
    """

    index: int
    time: float
    speed: float
    attack_angle: float
    total_attack_angle: float
    tip_depth: float
    position: np.ndarray
    velocity: np.ndarray
    rotation: np.ndarray
    sigma_n: np.ndarray
    tau: np.ndarray | None
    normal_velocity: np.ndarray
    point_sigma_n: np.ndarray = field(repr=False)
    hidden: np.ndarray = field(repr=False, default_factory=lambda: np.zeros(0, dtype=bool))

    def title(self, label: str = "") -> str:
        """One line: instant, time, speed, attack angle and tip depth."""
        head = f"{label}   " if label else ""
        return (
            f"{head}t = {self.time * 1e3:.2f} ms   V = {self.speed:.0f} m/s   "
            f"attack {self.attack_angle:+.2f} deg   tip depth {self.tip_depth:.2f} m"
        )


class FieldEvaluator:
    """Evaluates the resistance field of a finished run at any recorded step.

    Parameters
    ----------
    result : RunResult
        The run.
    history : DataFrame, optional
        Its :func:`~cases.run.history_table` (computed when not given).
    """

    def __init__(self, result: RunResult, history: pd.DataFrame | None = None) -> None:
        self.result = result
        self.history = history_table(result) if history is None else history
        self.prepared = result.prepared
        self.loads: DAFLLoads = result.scene.loads(result.prepared.quadrature)
        self.surface = surface_mesh(result.prepared, result.scene.numerics)
        per = self.surface.points_per_facet
        self._weights = result.prepared.quadrature.weights.reshape(-1, per)
        self._areas = self._weights.sum(axis=1)
        self.rotations = np.array([rotation_matrix(a) for a in result.trajectory.attitude])
        self.length = result.prepared.length

    @property
    def friction(self) -> bool:
        """Whether the scene has a tangential stress."""
        return self.loads.friction is not None

    def __len__(self) -> int:
        return len(self.result.trajectory.time)

    def _facet_mean(self, values: np.ndarray) -> np.ndarray:
        return (values.reshape(self._weights.shape) * self._weights).sum(axis=1) / self._areas

    def at(self, index: int) -> SurfaceField:
        """The field at trajectory row ``index`` (negative counts from the end)."""
        tr = self.result.trajectory
        index = range(len(tr.time))[index]
        position, velocity = tr.position[index], tr.velocity[index]
        stress = self.loads.surface_stress(position, velocity, self.rotations[index], tr.angular_velocity[index])
        tau = None if stress.tau is None else self._facet_mean(stress.tau)
        row = self.history.iloc[index]
        return SurfaceField(
            index,
            float(tr.time[index]),
            float(row["speed"]),
            float(row["attack_angle"]),
            float(row["total_attack_angle"]),
            float(row["tip_depth"]),
            position.copy(),
            velocity.copy(),
            self.rotations[index].copy(),
            self._facet_mean(stress.sigma_n),
            tau,
            self._facet_mean(stress.normal_velocity),
            stress.sigma_n,
            self._facet_mean((1.0 - stress.exposure) * (stress.normal_velocity > 0.0)) > 0.5,
        )

    def world_points(self, index: int) -> np.ndarray:
        """Vertices of the drawn surface in the world frame at row ``index`` (m)."""
        tr = self.result.trajectory
        return self.surface.points @ self.rotations[index].T + tr.position[index]

    def tip(self, index: int) -> np.ndarray:
        """The nose tip in the world frame (m)."""
        return self.rotations[index] @ self.prepared.tip + self.result.trajectory.position[index]

    def cell_values(self, values: np.ndarray) -> np.ndarray:
        """Facet values repeated onto the drawn triangles."""
        return values[self.surface.facet]


def _nose_embedded_index(evaluator: FieldEvaluator) -> int | None:
    """First row at which every quadrature point of the nose is below the surface."""
    prepared = evaluator.prepared
    q = prepared.quadrature
    behind_tip = prepared.tip[0] - q.points[:, 0]
    nose = q.points[behind_tip <= prepared.nose_length * (1 + 1e-9)]
    tr = evaluator.result.trajectory
    up = evaluator.rotations[:, 2, :]  # world Z of the body axes, one row per step
    for start in range(0, len(up), 512):
        highest = tr.position[start : start + 512, 2] + (up[start : start + 512] @ nose.T).max(axis=1)
        inside = np.flatnonzero(highest < 0.0)
        if len(inside):
            return start + int(inside[0])
    return None


def key_instants(evaluator: FieldEvaluator, threshold: float | None = None, unique: bool = True) -> dict[str, int]:
    """The rows of the default instants, in time order.

    ``embedded``: the first step with the whole nose below the surface (absent if it never is);
    ``peak``: the peak attack angle (:func:`~cases.run.attack_angle_peak`; absent if the
    attack angle stays below ``threshold``, as in purely axial motion); ``converged``: the first
    step after the peak with the total attack angle below ``threshold`` (the rule of
    :func:`~cases.run.convergence_speed`; absent if it never falls below, or if the peak is
    absent: nothing converged); ``end``: the last step.

    Parameters
    ----------
    evaluator : FieldEvaluator
        The run.
    threshold : float, optional
        Convergence threshold (deg); :data:`~cases.run.CONVERGENCE_THRESHOLD` by default.
    unique : bool
        Instants that fall on the same step keep only the first name.

    Returns
    -------
    dict
        Name to trajectory row, in time order.
    """
    threshold = CONVERGENCE_THRESHOLD if threshold is None else threshold
    history = evaluator.history
    rows: dict[str, int] = {}
    embedded = _nose_embedded_index(evaluator)
    if embedded is not None:
        rows["embedded"] = embedded
    angle = history["total_attack_angle"].to_numpy()
    peak = attack_angle_peak(history)
    if angle[peak] >= threshold:
        rows["peak"] = peak
        below = np.flatnonzero(angle[peak:] < threshold)
        if len(below):
            rows["converged"] = peak + int(below[0])
    rows["end"] = len(history) - 1
    ordered = dict(sorted(rows.items(), key=lambda item: item[1]))
    if not unique:
        return ordered
    kept: dict[str, int] = {}
    for name, row in ordered.items():
        if row not in kept.values():
            kept[name] = row
    return kept


def resolve_instants(evaluator: FieldEvaluator, spec: Sequence[str] | None) -> list[tuple[str, int]]:
    """Labels and rows of instants given by name (:data:`INSTANT_NAMES`) or time in seconds.

    A time picks the nearest recorded step.  None gives the default instants.

    Raises
    ------
    InputError
        For an unknown name, a time outside the run, or a named instant the run does not have.
    """
    if not spec:
        return [(INSTANT_LABELS[name], row) for name, row in key_instants(evaluator).items()]
    known = key_instants(evaluator, unique=False)
    known.setdefault("peak", attack_angle_peak(evaluator.history))  # asked for by name: even a small one
    times = evaluator.result.trajectory.time
    out = []
    for item in spec:
        text = str(item).strip()
        if text in INSTANT_NAMES:
            if text not in known:
                raise InputError(f"--times {text}: this run has no such instant (it has {', '.join(known)})")
            out.append((INSTANT_LABELS[text], known[text]))
            continue
        try:
            t = float(text)
        except ValueError:
            raise InputError(
                f"--times {text!r}: expected a time in seconds or one of {', '.join(INSTANT_NAMES)}"
            ) from None
        if not (times[0] <= t <= times[-1]):
            raise InputError(f"--times {text}: outside the run ({times[0]:g} .. {times[-1]:.6g} s)")
        out.append(("", int(np.argmin(np.abs(times - t)))))
    return out


def frame_rows(evaluator: FieldEvaluator, frames: int | None) -> np.ndarray:
    """``frames`` rows evenly spaced in time (nearest recorded steps, first and last kept); None: every row."""
    times = evaluator.result.trajectory.time
    if frames is None or frames >= len(times):
        return np.arange(len(times))
    wanted = np.linspace(times[0], times[-1], frames)
    rows = np.clip(np.searchsorted(times, wanted), 0, len(times) - 1)
    lower = np.maximum(rows - 1, 0)
    rows = np.where(np.abs(times[lower] - wanted) < np.abs(times[rows] - wanted), lower, rows)
    return np.unique(rows)
