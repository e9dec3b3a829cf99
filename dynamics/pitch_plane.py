"""Rigid-body motion in a plane through the body's axis, compiled: Dormand-Prince 5(4) with its events.

The reduced model of ``penetrate predict`` (docs/theory.md) moves a body of revolution in the vertical plane only:
three degrees of freedom instead of six, so neither quaternions nor the Munthe-Kaas step of
:mod:`dynamics.integrators` are needed.  The state is

    ``y = (X, Z, phi, v_X, v_Z, q)``

with the centre of mass at ``(X, Z)`` (m, world frame, ``Z`` up), the axis angle ``phi`` (rad: the body axis from
the downward vertical towards ``+X``, the paper's angle; the axis points along ``(sin phi, -cos phi)`` in ``X, Z``),
the velocity ``(v_X, v_Z)`` (m/s) and the pitch rate ``q`` about the body's y axis (rad/s; ``d phi / dt = -q``).
Newton-Euler: ``m dv/dt = R F - m g e_Z``, ``I dq/dt = M_y``, with ``F = (F_x, F_z)`` and ``M_y`` from a load
kernel in the body frame.  The body is turned by ``theta = pi/2 - phi`` about the world ``Y`` axis; a straight
downward axis is ``phi = 0`` exactly, so its sine and cosine are exact and a symmetric start stays exactly straight.

:func:`trajectory` steps by :class:`~dynamics.integrators.DormandPrince54`'s tableau under
:class:`~dynamics.control.ErrorControl`'s rule, with a compiled load kernel and lowest point (:data:`PlaneLoad`,
:data:`LowestPoint`) as arguments, inlined where they are globals as in :mod:`dynamics.compiled_rk`.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from numba import njit

from .control import step_factor_scalars
from .convergence import crossing_speed_scalars
from .integrators import DormandPrince54
from .rigid_body import euler_scalars

__all__ = [
    "trajectory",
    "PlaneBody",
    "PlaneSteps",
    "PlaneEnds",
    "STOPPED",
    "EXITED",
    "TURNED",
    "TIME_LIMIT",
    "CONVERGED",
    "END_REASONS",
    "OUTCOME_FIELDS",
]

STOPPED, EXITED, TURNED, TIME_LIMIT, CONVERGED = 0, 1, 2, 3, 4
END_REASONS = ("stopped", "exited", "turned", "time_limit", "converged")
#: what :func:`trajectory` returns, in order
OUTCOME_FIELDS = (
    "end",
    "time",
    "final_speed",
    "axis_turn",
    "max_attack_angle",
    "speed_at_max_attack",
    "convergence_speed",
    "steps",
    "rejected_steps",
    "evaluations",
)
_A, _B_ERROR = np.ascontiguousarray(DormandPrince54.A), np.ascontiguousarray(DormandPrince54.b_error)
_STATES = 6

#: ``load(data, height, sin_theta, cos_theta, v_x, v_z, q, out)``: ``F_x``, ``F_z`` (N) and ``M_y`` (N m, body
#: frame) into ``out`` (:func:`fem_loads.kernels.rings.pitch_plane_load`)
PlaneLoad = Callable[[tuple[np.ndarray, ...], float, float, float, float, float, float, np.ndarray], None]
#: ``lowest(data, height, sin_theta, cos_theta)``: the height (m) of the body's lowest point
LowestPoint = Callable[[tuple[np.ndarray, ...], float, float, float], float]


class PlaneBody(NamedTuple):
    """The body as :func:`trajectory` moves it."""

    mass: float  #: kg
    inertia: float  #: kg m^2: the transverse moment of inertia about the centre of mass
    gravity: float  #: m/s^2, downward (0: none)


class PlaneSteps(NamedTuple):
    """The step control of :func:`trajectory`."""

    rtol: float  #: the relative tolerance
    scales: np.ndarray  #: (6,): the absolute tolerances over ``rtol``
    first_step: float  #: s
    max_step: float  #: s: events are not located (a run ends at the first step past one), so this bounds the overrun


class PlaneEnds(NamedTuple):
    """When :func:`trajectory` ends a run besides the body's leaving the target."""

    stop_speed: float  #: m/s
    time_limit: float  #: s
    turn_limit: float  #: rad: the axis turn ``|phi - phi_0|``
    threshold: float  #: rad: the attack angle below which, after its peak, the run has converged
    peak_floor: float  #: m/s: the peak is sought while the speed is at least this (a tenth of the impact speed)
    stop_when_converged: bool  #: end the run at convergence


# Newton-Euler, the full model's step control and its convergence rule, compiled from the same source
_euler_scalars = njit(inline="always", error_model="numpy")(euler_scalars)
_step_factor = njit(inline="always", error_model="numpy")(step_factor_scalars)
_crossing_speed = njit(inline="always", error_model="numpy")(crossing_speed_scalars)


@njit(cache=True, inline="always")
def _derivative(
    load: PlaneLoad, data: tuple[np.ndarray, ...], y: np.ndarray, body: PlaneBody, out: np.ndarray, loads: np.ndarray
) -> None:
    """``dy/dt`` at ``y`` into ``out`` (``loads``: a 3-vector to use for the body-frame load)."""
    mass, inertia, gravity = body
    sin_t, cos_t = math.cos(y[2]), math.sin(y[2])  # theta = pi/2 - phi
    vx = cos_t * y[3] - sin_t * y[4]  # body frame: R^T v
    vz = sin_t * y[3] + cos_t * y[4]
    load(data, y[1], sin_t, cos_t, vx, vz, y[5], loads)
    out[0], out[1], out[2] = y[3], y[4], -y[5]
    out[3] = (cos_t * loads[0] + sin_t * loads[1]) / mass
    out[4] = (-sin_t * loads[0] + cos_t * loads[1]) / mass - gravity
    # Euler's equation about the pitch axis: the spin vector lies on it, so omega x (I omega) vanishes
    out[5] = _euler_scalars(
        (0.0, loads[2], 0.0),
        (0.0, y[5], 0.0),
        (1.0, 0.0, 0.0, 0.0, inertia, 0.0, 0.0, 0.0, 1.0),
        (1.0, 0.0, 0.0, 0.0, 1.0 / inertia, 0.0, 0.0, 0.0, 1.0),
    )[1]


@njit(cache=True, inline="always")
def _attack_angle(y: np.ndarray) -> float:
    """The angle between the body axis and the velocity (rad, >= 0)."""
    sin_t, cos_t = math.cos(y[2]), math.sin(y[2])
    return abs(math.atan2(sin_t * y[3] + cos_t * y[4], cos_t * y[3] - sin_t * y[4]))


@njit(cache=True, inline="always")
def trajectory(
    load: PlaneLoad,
    lowest: LowestPoint,
    data: tuple[np.ndarray, ...],
    y0: np.ndarray,
    body: PlaneBody,
    control: PlaneSteps,
    ends: PlaneEnds,
) -> tuple[int, float, float, float, float, float, float, int, int, int]:
    """Integrate from ``y0`` (``(X, Z, phi, v_X, v_Z, q)``) to an end; returns the :data:`OUTCOME_FIELDS` (SI units,
    angles in rad).  ``load`` and ``lowest`` are given ``data``.  The run ends when the body stops (speed below
    ``stop_speed``), leaves the target (its lowest point back above the surface after having been in), its axis has
    turned by ``turn_limit``, the time limit passes, or, when asked, the attack angle has converged
    (:mod:`dynamics.convergence`)."""
    rtol, scales, first_step, max_step = control
    stop_speed, time_limit, turn_limit, threshold, peak_floor, stop_when_converged = ends
    k = np.empty((7, _STATES))
    y = y0.copy()
    trial = np.empty(_STATES)
    loads = np.empty(3)
    _derivative(load, data, y, body, k[0], loads)
    evaluations, steps, rejected = 1, 0, 0
    t, h = 0.0, min(first_step, max_step)
    speed = math.hypot(y[3], y[4])
    attack = _attack_angle(y)
    peak, speed_at_peak, converged_at = attack, speed, -1.0
    entered = lowest(data, y[1], math.cos(y[2]), math.sin(y[2])) < 0.0
    end = TIME_LIMIT
    while t < time_limit:
        for stage in range(1, 7):
            for i in range(_STATES):
                total = 0.0
                for j in range(stage):
                    total += _A[stage, j] * k[j, i]
                trial[i] = y[i] + h * total
            _derivative(load, data, trial, body, k[stage], loads)
        evaluations += 6
        error = 0.0
        for i in range(_STATES):
            estimate = 0.0
            for j in range(7):
                estimate += _B_ERROR[j] * k[j, i]
            scaled = h * estimate / (rtol * (scales[i] + abs(y[i])))
            error += scaled * scaled
        error = math.sqrt(error / _STATES)
        if not error <= 1.0:  # NaN fails too
            rejected += 1
            h *= _step_factor(error, -0.2)
            continue
        t += h
        steps += 1
        y[:] = trial  # the last stage is the solution (first same as last)
        k[0, :] = k[6, :]
        h = min(h * _step_factor(error, -0.2), max_step)
        h = min(h, time_limit - t) if time_limit > t else h
        previous_attack, previous_speed = attack, speed
        speed = math.hypot(y[3], y[4])
        attack = _attack_angle(y)
        if attack > peak and speed >= peak_floor:
            peak, speed_at_peak, converged_at = attack, speed, -1.0
        elif converged_at < 0.0 and peak >= threshold and attack < threshold <= previous_attack:
            converged_at = _crossing_speed(previous_attack, attack, previous_speed, speed, threshold)
        inside = lowest(data, y[1], math.cos(y[2]), math.sin(y[2])) < 0.0
        if entered and not inside:
            end = EXITED
        elif speed < stop_speed:
            end = STOPPED
        elif abs(y[2] - y0[2]) >= turn_limit:
            end = TURNED
        elif stop_when_converged and converged_at >= 0.0:
            end = CONVERGED
        if end != TIME_LIMIT:  # one of the ends is met
            break
        entered = entered or inside
    return end, t, math.hypot(y[3], y[4]), y[2] - y0[2], peak, speed_at_peak, converged_at, steps, rejected, evaluations
