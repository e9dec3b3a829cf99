"""Explicit Runge-Kutta methods on the rigid-body state (Runge-Kutta-Munthe-Kaas; docs/numerics.md).

Within one step the attitude is ``q = q0 * exp(u)`` with a rotation vector ``u`` that starts at zero, so the step
integrates a plain ODE for ``(x, v, u, omega)``: ``du/dt = dexp^-1_u(omega)``
(:func:`~dynamics.quaternion.right_jacobian_inverse`), which keeps the classical order of the tableau.  The new
attitude ``q0 * exp(u1)`` is renormalised once per step; the path length ``s`` is measured on the step's chord
(:func:`path_increment_scalars`).  A step whose state leaves the floats returns a non-finite state instead of
raising, so that the caller ends the run with its history.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import NamedTuple, Protocol

import numpy as np

from .quaternion import compose, normalize, right_jacobian_inverse, rotation_matrix
from .rigid_body import LoadFunction, RigidBody, State

__all__ = ["Stepper", "RungeKutta", "RK4", "DormandPrince54", "Evaluation", "StepResult", "METHODS"]

# layout of the increment vector z = (x, v, u, omega, s) used inside a step (s the last)
POSITION, VELOCITY, ROTATION, ANGULAR_VELOCITY = slice(0, 3), slice(3, 6), slice(6, 9), slice(9, 12)
N_INCREMENTS = 13


class Evaluation(NamedTuple):
    """Loads and accelerations at one state (one call of the load function)."""

    acceleration: np.ndarray  # world frame (m/s^2)
    angular_acceleration: np.ndarray  # body frame (rad/s^2)
    force: np.ndarray  # world frame (N)
    moment: np.ndarray  # body frame, about the centre of mass (N m)


def evaluate(
    body: RigidBody,
    loads: LoadFunction,
    position: np.ndarray,
    velocity: np.ndarray,
    attitude: np.ndarray,
    angular_velocity: np.ndarray,
) -> Evaluation:
    """Call the load function once and apply Newton-Euler."""
    force, moment = loads(position, velocity, rotation_matrix(attitude), angular_velocity)
    acceleration, angular_acceleration = body.accelerations(force, moment, angular_velocity)
    return Evaluation(acceleration, angular_acceleration, force, moment)


@dataclass(frozen=True)
class StepResult:
    """Outcome of one Runge-Kutta step."""

    state: State  # at the end of the step
    error: np.ndarray | None  # local error estimate of the increments (x, v, u, omega, s), for embedded pairs
    # the evaluation at the start of the step (reusable after a rejection); None when the step left the floats
    # before it had one
    first: Evaluation | None
    last: Evaluation | None  # for first-same-as-last methods, the evaluation at the end of the step
    evaluations: int = 0  # calls of the load function the step made


def path_increment_scalars(
    cx: float, cy: float, cz: float, ax: float, ay: float, az: float, bx: float, by: float, bz: float
) -> float:
    """Length (m) of the centre of mass's path over a step of chord ``c`` from velocity ``a`` to ``b``.

    The chord ``|c|`` lengthened by ``theta^2 / 24``, ``theta`` the angle between ``a`` and ``b``: exact for a
    straight or circular path up to ``O(theta^4)``.  Not ``int |v| dt`` by the step's quadrature, whose stage
    velocities swing sideways across a jump of the load (docs/numerics.md, "Time integration").
    """
    length = math.sqrt(cx * cx + cy * cy + cz * cz)
    dot = ax * bx + ay * by + az * bz
    cross2 = (ay * bz - az * by) ** 2 + (az * bx - ax * bz) ** 2 + (ax * by - ay * bx) ** 2
    theta = math.atan2(math.sqrt(cross2), dot) if dot != 0.0 or cross2 != 0.0 else 0.0
    return length * (1.0 + theta * theta / 24.0)


class Stepper(Protocol):
    """What the driver (:func:`~dynamics.simulate.simulate`) and the step control ask of a method: a
    :class:`RungeKutta`, or the compiled step that wraps one (:class:`~dynamics.compiled_rk.CompiledRungeKutta`)."""

    error_order: int

    @property
    def adaptive(self) -> bool: ...

    def step(
        self, body: RigidBody, loads: LoadFunction, state: State, h: float, first: Evaluation | None = None
    ) -> StepResult: ...


class RungeKutta:
    """Base class of explicit Runge-Kutta methods on the rigid-body state.

    Contract: :meth:`step` advances a :class:`~dynamics.rigid_body.State` by ``h`` seconds, calling the load
    function once per stage (once less when the first evaluation is passed in), and returns a
    :class:`StepResult` whose attitude is a unit quaternion to round-off.  Subclasses set only the class
    attributes.
    """

    A: np.ndarray  # Runge-Kutta matrix, shape (stages, stages), strictly lower triangular
    b: np.ndarray  # weights of the solution, shape (stages,)
    c: np.ndarray  # nodes, shape (stages,)
    b_error: np.ndarray | None = None  # b - b_hat: weights of the embedded error estimate, or None
    order: int  # of the solution
    error_order: int = 0  # of the embedded estimate (the step-size control uses 1/(error_order + 1))
    fsal: bool = False  # first same as last: the last stage is evaluated at the end of the step

    @property
    def adaptive(self) -> bool:
        return self.b_error is not None

    def step(
        self, body: RigidBody, loads: LoadFunction, state: State, h: float, first: Evaluation | None = None
    ) -> StepResult:
        """Advance ``state`` by ``h`` seconds."""
        x0, v0, q0, w0 = state.position, state.velocity, state.attitude, state.angular_velocity
        # the increments' start (x0, v0, 0, omega0, 0): one add per stage gives every stage state
        start = np.zeros(N_INCREMENTS)
        start[POSITION], start[VELOCITY], start[ANGULAR_VELOCITY] = x0, v0, w0
        k = np.zeros((len(self.b), N_INCREMENTS))  # the path column stays 0: see path_increment_scalars
        evaluations: list[Evaluation] = []
        calls = 0
        try:
            for i in range(len(self.b)):
                if i:
                    z = start + (h * self.A[i, :i]) @ k[:i]
                    x, v, u, w = z[POSITION], z[VELOCITY], z[ROTATION], z[ANGULAR_VELOCITY]
                    e = evaluate(body, loads, x, v, compose(q0, u), w)
                    calls += 1
                    rate = right_jacobian_inverse(u, w)
                else:
                    v, rate = v0, w0
                    e = evaluate(body, loads, x0, v0, q0, w0) if first is None else first
                    calls += first is None
                evaluations.append(e)
                row = k[i]
                row[POSITION], row[VELOCITY] = v, e.acceleration
                row[ROTATION], row[ANGULAR_VELOCITY] = rate, e.angular_acceleration
            z = h * (self.b @ k)
            attitude = normalize(compose(q0, z[ROTATION]))
        except (ValueError, OverflowError, ZeroDivisionError):
            # math.sin of an infinite rotation, or |q| = 0: the state left the floats inside the step
            nan = np.full(3, np.nan)
            new = State(state.time + h, nan, nan, np.full(4, np.nan), nan, math.nan)
            error = np.full(N_INCREMENTS, np.inf) if self.b_error is not None else None
            return StepResult(new, error, evaluations[0] if evaluations else first, None, calls)
        velocity, chord = v0 + z[VELOCITY], z[POSITION]
        path_length = state.path_length + path_increment_scalars(*chord.tolist(), *v0.tolist(), *velocity.tolist())
        new = State(state.time + h, x0 + chord, velocity, attitude, w0 + z[ANGULAR_VELOCITY], path_length)
        error = h * (self.b_error @ k) if self.b_error is not None else None
        return StepResult(new, error, evaluations[0], evaluations[-1] if self.fsal else None, calls)


class RK4(RungeKutta):
    """The classical fourth-order Runge-Kutta method (fixed step)."""

    A = np.array([[0, 0, 0, 0], [0.5, 0, 0, 0], [0, 0.5, 0, 0], [0, 0, 1, 0]], dtype=float)
    b = np.array([1, 2, 2, 1], dtype=float) / 6
    c = np.array([0, 0.5, 0.5, 1], dtype=float)
    order = 4


class DormandPrince54(RungeKutta):
    """Dormand-Prince 5(4) with first-same-as-last stage (adaptive step)."""

    A = np.array(
        [
            [0, 0, 0, 0, 0, 0, 0],
            [1 / 5, 0, 0, 0, 0, 0, 0],
            [3 / 40, 9 / 40, 0, 0, 0, 0, 0],
            [44 / 45, -56 / 15, 32 / 9, 0, 0, 0, 0],
            [19372 / 6561, -25360 / 2187, 64448 / 6561, -212 / 729, 0, 0, 0],
            [9017 / 3168, -355 / 33, 46732 / 5247, 49 / 176, -5103 / 18656, 0, 0],
            [35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0],
        ]
    )
    b = np.array([35 / 384, 0, 500 / 1113, 125 / 192, -2187 / 6784, 11 / 84, 0])
    c = np.array([0, 1 / 5, 3 / 10, 4 / 5, 8 / 9, 1, 1])
    b_error = b - np.array([5179 / 57600, 0, 7571 / 16695, 393 / 640, -92097 / 339200, 187 / 2100, 1 / 40])
    order = 5
    error_order = 4
    fsal = True


METHODS: dict[str, type[RungeKutta]] = {"rk4": RK4, "dopri54": DormandPrince54}
