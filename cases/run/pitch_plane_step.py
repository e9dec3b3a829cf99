"""The compiled reduced trajectory: the pitch-plane driver of :mod:`dynamics.pitch_plane` with the ring load of
:mod:`fem_loads.kernels.rings` (imported through :func:`.compiled.use_numba_cache` first, which names numba's cache
folder for this code).  The load is a global here, so numba can cache the whole trajectory."""

from __future__ import annotations

import numpy as np
from numba import njit

from dynamics.pitch_plane import PlaneBody, PlaneEnds, PlaneSteps, trajectory
from fem_loads.kernels.rings import lowest_height, pitch_plane_load

__all__ = ["pitch_plane_trajectory", "pitch_plane_turns"]


@njit(cache=True, inline="always")
def _load(
    data: tuple[np.ndarray, ...],
    height: float,
    sin_theta: float,
    cos_theta: float,
    vx: float,
    vz: float,
    q: float,
    out: np.ndarray,
) -> None:
    pitch_plane_load(data[0], data[1], data[2], (height, sin_theta, cos_theta, vx, vz, q), out)


@njit(cache=True, inline="always")
def _lowest(data: tuple[np.ndarray, ...], height: float, sin_theta: float, cos_theta: float) -> float:
    return lowest_height(data[3], height, sin_theta, cos_theta)


@njit(cache=True, error_model="numpy")
def pitch_plane_trajectory(
    rings: np.ndarray,
    laws: np.ndarray,
    effects: np.ndarray,
    outline: np.ndarray,
    y0: np.ndarray,
    body: PlaneBody,
    control: PlaneSteps,
    ends: PlaneEnds,
) -> tuple[int, float, float, float, float, float, float, int, int, int]:
    """:func:`dynamics.pitch_plane.trajectory` with the load :func:`fem_loads.kernels.rings.pitch_plane_load` on
    ``rings`` under the records ``laws`` and ``effects`` (:func:`fem_loads.kernels.rings.ring_data`; the lowest point on
    ``outline``); returns its :data:`~dynamics.pitch_plane.OUTCOME_FIELDS`."""
    return trajectory(_load, _lowest, (rings, laws, effects, outline), y0, body, control, ends)


@njit(cache=True, error_model="numpy")
def pitch_plane_turns(
    rings: np.ndarray,
    laws: np.ndarray,
    effects: np.ndarray,
    outline: np.ndarray,
    starts: np.ndarray,
    body: PlaneBody,
    controls: tuple[float, np.ndarray, np.ndarray, float],
    ends: tuple[np.ndarray, float, float, float, np.ndarray, bool],
) -> np.ndarray:
    """The axis turn (rad) of :func:`pitch_plane_trajectory` from each row of ``starts`` (shape ``(n, 6)``), in one
    call: :class:`~dynamics.pitch_plane.PlaneSteps` and :class:`~dynamics.pitch_plane.PlaneEnds` with one row or
    entry per run where they depend on its speed (the scales, first step, stop speed and peak floor)."""
    rtol, scales, first_steps, max_step = controls
    stop_speeds, time_limit, turn_limit, threshold, peak_floors, stop_when_converged = ends
    turns = np.empty(len(starts))
    for i in range(len(starts)):
        outcome = trajectory(
            _load,
            _lowest,
            (rings, laws, effects, outline),
            starts[i],
            body,
            PlaneSteps(rtol, scales[i], first_steps[i], max_step),
            PlaneEnds(stop_speeds[i], time_limit, turn_limit, threshold, peak_floors[i], stop_when_converged),
        )
        turns[i] = outcome[3]
    return turns
