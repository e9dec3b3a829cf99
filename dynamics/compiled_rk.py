"""Runge-Kutta steps in compiled code (numba): the whole stage loop, for a load with a compiled kernel.

:class:`CompiledRungeKutta` keeps the contract of :class:`~dynamics.integrators.RungeKutta` (same tableau,
Runge-Kutta-Munthe-Kaas step and chord path increment), but one call of :func:`rk_step` does every stage of a
step in machine code, the load kernel of a :class:`CompiledLoad` included; the driver
(:func:`~dynamics.simulate.simulate`) sees one :class:`StepResult` per step as before.  The quaternion and path
arithmetic is the Python step's own ``*_scalars`` functions, compiled; the stage sums and the load run in
another order, so the two steps agree to round-off, not bit for bit (tests/dynamics/test_compiled_rk.py).
Caching and its costs: docs/numerics.md, "The compiled step", and docs/dev-numerics.md.
"""

from __future__ import annotations

import math
from collections.abc import Callable

import numpy as np
from numba import njit

from .integrators import Evaluation, RungeKutta, StepResult, path_increment_scalars
from .quaternion import dexp_inverse_scalars, exp_scalars, hamilton_scalars, rotation_scalars
from .rigid_body import LoadFunction, RigidBody, State, euler_scalars

__all__ = ["CompiledLoad", "CompiledRungeKutta", "rk_step"]

# layout of the array rk_step fills: the state, the error estimate, the first and last evaluations
_X, _V, _Q, _W, _S = slice(0, 3), slice(3, 6), slice(6, 10), slice(10, 13), 13
_ERROR = slice(14, 27)
_FIRST, _LAST = 27, 39  # each: acceleration (3), angular acceleration (3), force (3), moment (3)
_OUT = 51

#: a load kernel's arrays and constants
KernelData = tuple[np.ndarray, ...]
# ``kernel(data, position, velocity, rotation, angular_velocity, out)`` of a CompiledLoad (a numba dispatcher)
LoadKernel = Callable[[KernelData, np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], None]
#: the body as the step takes it: constant force (N, world frame), mass (kg), inertia tensor and its inverse
#: (kg m^2, body frame)
Body = tuple[np.ndarray, float, np.ndarray, np.ndarray]
#: the method's tableau: ``A``, ``b``, ``b_error`` (zeros without an estimate), first-same-as-last
Tableau = tuple[np.ndarray, np.ndarray, np.ndarray, bool]
#: the state at a step's start: position, velocity, unit attitude quaternion, angular velocity
Start = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]


class CompiledLoad:
    """A load function with a compiled kernel, callable from Python and from the compiled step.

    Parameters
    ----------
    kernel : numba dispatcher
        ``kernel(data, position, velocity, rotation, angular_velocity, out)`` writes the force (world frame, N)
        into ``out[:3]`` and the moment (body frame, about the centre of mass, N m) into ``out[3:6]``; arguments
        as for :class:`~dynamics.rigid_body.LoadFunction`.
    data : tuple
        The kernel's arrays and constants.
    step : numba dispatcher
        :func:`rk_step` with this kernel, made in a module of its own by::

            @njit(cache=True, error_model="numpy")
            def step(data, body, method, start, h, given, has_given, out):
                rk_step(kernel, data, body, method, start, h, given, has_given, out)

        The kernel is a global there, so numba can cache the machine code; a step taking the kernel as an
        argument from Python would be compiled anew by every process (numba keys such code on the kernel
        object's identity).
    constant_force : ndarray, shape (3,), optional
        A force added to the kernel's (world frame, N): the weight of the body.
    """

    def __init__(
        self, kernel: LoadKernel, data: KernelData, step: Callable[..., None], constant_force: np.ndarray | None = None
    ) -> None:
        self.kernel, self.data, self.step = kernel, data, step
        self.constant_force = np.zeros(3) if constant_force is None else np.asarray(constant_force, dtype=float)

    def __call__(
        self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        out = np.empty(6)
        self.kernel(self.data, position, velocity, rotation, angular_velocity, out)
        return out[:3] + self.constant_force, out[3:]


class CompiledRungeKutta:
    """The compiled step of the Runge-Kutta ``method`` (its tableau, stepped by :func:`rk_step`): a
    :class:`~dynamics.integrators.Stepper` like ``method``, whose :meth:`step` takes a :class:`CompiledLoad`."""

    def __init__(self, method: RungeKutta) -> None:
        self.method = method
        self.adaptive, self.error_order = method.adaptive, method.error_order
        b_error = np.zeros_like(method.b) if method.b_error is None else method.b_error
        A, b, b_error = (np.ascontiguousarray(array, dtype=float) for array in (method.A, method.b, b_error))
        self._tableau: Tableau = (A, b, b_error, bool(method.fsal))
        self._matrices: tuple[RigidBody, np.ndarray, np.ndarray] | None = None  # a body, its inertia and inverse

    def step(
        self, body: RigidBody, loads: LoadFunction, state: State, h: float, first: Evaluation | None = None
    ) -> StepResult:
        """Advance ``state`` by ``h`` seconds (see :class:`~dynamics.integrators.RungeKutta`); ``loads`` is a
        :class:`CompiledLoad`."""
        if not isinstance(loads, CompiledLoad):
            raise TypeError("a compiled step takes a CompiledLoad, whose own step runs its kernel")
        if self._matrices is None or self._matrices[0] is not body:
            inertia = np.ascontiguousarray(body.inertia, dtype=float)
            self._matrices = (body, inertia, np.ascontiguousarray(np.linalg.inv(inertia)))
        _, inertia, inverse = self._matrices
        given = np.empty(12) if first is None else np.concatenate(first)  # the fields of an Evaluation, in order
        body_data: Body = (loads.constant_force, body.mass, inertia, inverse)
        start: Start = (state.position, state.velocity, state.attitude, state.angular_velocity)
        out = np.empty(_OUT)
        loads.step(loads.data, body_data, self._tableau, start, h, given, first is not None, out)
        new = State(state.time + h, out[_X], out[_V], out[_Q], out[_W], state.path_length + out[_S])
        error = out[_ERROR] if self.adaptive else None
        # without a first-same-as-last stage the step evaluates the end state too: the driver needs it for
        # the next step and the history, and it costs less here than from Python
        evaluations = len(self.method.b) - (first is not None) + (not self.method.fsal)
        first = first if first is not None else _evaluation(out, _FIRST)
        return StepResult(new, error, first, _evaluation(out, _LAST), evaluations)


def _evaluation(out: np.ndarray, at: int) -> Evaluation:
    return Evaluation(out[at : at + 3], out[at + 3 : at + 6], out[at + 6 : at + 9], out[at + 9 : at + 12])


# -- compiled ---------------------------------------------------------------------------------------
# error_model="numpy": a division by zero gives inf or nan (as numpy does) instead of raising, so a
# state that leaves the floats comes back non-finite and the step control ends the run.
# The arithmetic of the Python step (dynamics.quaternion, dynamics.integrators), compiled from the same source:
_exp_scalars = njit(inline="always", error_model="numpy")(exp_scalars)
_hamilton_scalars = njit(inline="always", error_model="numpy")(hamilton_scalars)
_rotation_scalars = njit(inline="always", error_model="numpy")(rotation_scalars)
_dexp_inverse_scalars = njit(inline="always", error_model="numpy")(dexp_inverse_scalars)
_path_increment_scalars = njit(inline="always", error_model="numpy")(path_increment_scalars)
_euler_scalars = njit(inline="always", error_model="numpy")(euler_scalars)


@njit(inline="always", error_model="numpy")
def _compose(q: np.ndarray, u: np.ndarray, out: np.ndarray) -> None:
    """``out = q * exp(u)`` (:func:`dynamics.quaternion.compose`)."""
    qw, qx, qy, qz = _exp_scalars(u[0], u[1], u[2])
    out[0], out[1], out[2], out[3] = _hamilton_scalars(q[0], q[1], q[2], q[3], qw, qx, qy, qz)


@njit(inline="always", error_model="numpy")
def _evaluate(
    load: LoadKernel,
    data: KernelData,
    body: Body,
    x: np.ndarray,
    v: np.ndarray,
    q: np.ndarray,
    w: np.ndarray,
    rotation: np.ndarray,
    loads: np.ndarray,
    out: np.ndarray,
    at: int,
) -> None:
    """One load evaluation at the attitude ``q`` and Newton-Euler; ``out[at:at + 12]`` = (a, alpha, F, M)."""
    constant_force, mass, inertia, inverse = body
    r = _rotation_scalars(q[0], q[1], q[2], q[3])
    rotation[0, 0], rotation[0, 1], rotation[0, 2] = r[0], r[1], r[2]
    rotation[1, 0], rotation[1, 1], rotation[1, 2] = r[3], r[4], r[5]
    rotation[2, 0], rotation[2, 1], rotation[2, 2] = r[6], r[7], r[8]
    load(data, x, v, rotation, w, loads)
    for c in range(3):
        force = loads[c] + constant_force[c]
        out[at + 6 + c] = force
        out[at + 9 + c] = loads[3 + c]
        out[at + c] = force / mass
    i, j = inertia, inverse
    out[at + 3], out[at + 4], out[at + 5] = _euler_scalars(
        (loads[3], loads[4], loads[5]),
        (w[0], w[1], w[2]),
        (i[0, 0], i[0, 1], i[0, 2], i[1, 0], i[1, 1], i[1, 2], i[2, 0], i[2, 1], i[2, 2]),
        (j[0, 0], j[0, 1], j[0, 2], j[1, 0], j[1, 1], j[1, 2], j[2, 0], j[2, 1], j[2, 2]),
    )


@njit(inline="always", error_model="numpy")
def rk_step(
    load: LoadKernel,
    data: KernelData,
    body: Body,
    method: Tableau,
    start: Start,
    h: float,
    given: np.ndarray,
    has_given: bool,
    out: np.ndarray,
) -> None:
    """One explicit Runge-Kutta-Munthe-Kaas step from ``start`` by ``h`` seconds, inlined into the step of each load
    kernel (:class:`CompiledLoad`, ``step``), never called alone; ``given`` is the first stage's evaluation when
    ``has_given``.  Fills ``out`` (its layout at the module's top): the new state and path increment, the error
    estimate ``h (b_error . k)`` of the increments ``(x, v, u, omega, s)``, and the first and last evaluations; the
    last is the end state's (the last stage's when ``fsal``, an extra evaluation otherwise).
    """
    A, b, b_error, fsal = method
    x0, v0, q0, w0 = start
    stages = b.shape[0]
    k = np.zeros((stages, 13))
    z = np.empty(13)
    q = np.empty(4)
    rotation = np.empty((3, 3))
    loads = np.empty(6)
    evaluation = np.empty(_OUT)
    if has_given:
        out[_FIRST : _FIRST + 12] = given
    else:
        _evaluate(load, data, body, x0, v0, q0, w0, rotation, loads, out, _FIRST)
    for j in range(3):
        k[0, j] = v0[j]
        k[0, 3 + j] = out[_FIRST + j]
        k[0, 6 + j] = w0[j]
        k[0, 9 + j] = out[_FIRST + 3 + j]
    for i in range(1, stages):
        for j in range(13):
            total = 0.0
            for m in range(i):
                total += (h * A[i, m]) * k[m, j]
            z[j] = total
        for j in range(3):
            z[j] += x0[j]
            z[3 + j] += v0[j]
            z[9 + j] += w0[j]
        _compose(q0, z[6:9], q)
        at = _LAST if i == stages - 1 else 0
        source = evaluation if at == 0 else out
        _evaluate(load, data, body, z[0:3], z[3:6], q, z[9:12], rotation, loads, source, at)
        # du/dt = dexp^-1_u(omega)
        k[i, 6], k[i, 7], k[i, 8] = _dexp_inverse_scalars(z[6], z[7], z[8], z[9], z[10], z[11])
        for j in range(3):
            k[i, j] = z[3 + j]
            k[i, 3 + j] = source[at + j]
            k[i, 9 + j] = source[at + 3 + j]
    increment = np.empty(13)
    for j in range(13):
        total = error = 0.0
        for m in range(stages):
            total += b[m] * k[m, j]
            error += b_error[m] * k[m, j]
        increment[j] = h * total
        out[_ERROR.start + j] = h * error
    attitude = np.empty(4)
    _compose(q0, increment[6:9], attitude)
    w, x, y, zq = attitude[0], attitude[1], attitude[2], attitude[3]
    norm = math.sqrt((w * w + y * y) + (x * x + zq * zq))
    for j in range(4):
        out[6 + j] = attitude[j] / norm
    for j in range(3):
        out[j] = x0[j] + increment[j]
        out[3 + j] = v0[j] + increment[3 + j]
        out[10 + j] = w0[j] + increment[9 + j]
    out[_S] = _path_increment_scalars(
        increment[0], increment[1], increment[2], v0[0], v0[1], v0[2], out[3], out[4], out[5]
    )
    if not fsal:
        _evaluate(load, data, body, out[_X], out[_V], out[_Q], out[_W], rotation, loads, out, _LAST)
