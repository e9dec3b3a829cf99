"""The judges of a trial step in :func:`~dynamics.simulate.simulate`: the step-size controls (:class:`StepControl`)
and the energy guard (:class:`EnergyGuard`), for loads that can only remove energy."""

from __future__ import annotations

import math
from dataclasses import replace

import numpy as np

from .integrators import ANGULAR_VELOCITY, N_INCREMENTS, POSITION, VELOCITY, Stepper, StepResult
from .rigid_body import RigidBody, State

__all__ = [
    "StepControl",
    "FixedStep",
    "ErrorControl",
    "EnergyGuard",
    "ACCEPT",
    "RETAKE",
    "END",
    "NON_FINITE",
    "STEP_FLOOR",
    "ENERGY_TOLERANCE",
]

# the verdicts on a trial step
ACCEPT, RETAKE, END = "accept", "retake", "end"
NON_FINITE = "non_finite"
# the integration needed a step shorter than its floor: a numerical failure, the history up to it is kept
STEP_FLOOR = "step_floor"

# relative kinetic-energy gain above which a step of a dissipative system is retaken: far above round-off and the
# shank's sliding chatter, far below the pumping that lets a run creep near rest (docs/numerics.md, energy guard)
ENERGY_TOLERANCE = 1e-7


class StepControl:
    """Base class of step-size controls.

    Contract: :meth:`start` checks that the control suits the method and returns the first trial step (s); after
    each trial step of ``size`` from ``state``, :meth:`judge` returns a verdict and a value:

    * ``(ACCEPT, next_step)``: keep the step, try ``next_step`` next;
    * ``(RETAKE, shorter)``: retake the step from ``state`` with ``shorter``;
    * ``(END, reason)``: the run must end here (``NON_FINITE``, ``STEP_FLOOR``).

    Attributes
    ----------
    min_step : float
        The step floor (s): no step is retaken shorter than this.
    forced_steps : int
        Steps accepted although they failed the control's own test.
    """

    min_step: float
    forced_steps: int = 0

    def start(self, method: Stepper) -> float:
        raise NotImplementedError

    def judge(self, result: StepResult, state: State, size: float) -> tuple[str, float | str]:
        raise NotImplementedError


def _positive(name: str, value: float) -> float:
    if not (value > 0 and math.isfinite(value)):
        raise ValueError(f"{name} = {value}: must be a finite number > 0")
    return float(value)


class FixedStep(StepControl):
    """Steps of ``time_step`` seconds (the last one shortened to end at the time limit).

    A step whose state is not finite ends the run with :data:`NON_FINITE`.

    Parameters
    ----------
    time_step : float
        The step (s).
    min_step : float
        The step floor (s) of the energy guard's retakes (the only use of it here).
    """

    def __init__(self, time_step: float, min_step: float = 1e-10) -> None:
        self.time_step = _positive("time_step", time_step)
        self.min_step = _positive("min_step", min_step)

    def start(self, method: Stepper) -> float:
        return self.time_step

    def judge(self, result: StepResult, state: State, size: float) -> tuple[str, float | str]:
        return (ACCEPT, self.time_step) if result.state.is_finite() else (END, NON_FINITE)


def step_factor_scalars(norm: float, exponent: float) -> float:
    """The next step (or the retaken one) over this one, from the error norm of this one: ``0.9 norm^exponent``
    within 0.2 to 5 (``exponent = -1/(p + 1)``, p the order of the estimate); 5 for a zero norm, 0.2 for one
    that is infinite or not a number.  :class:`ErrorControl` calls it, :mod:`dynamics.pitch_plane` compiles it."""
    if 0.0 < norm < math.inf:
        return min(5.0, max(0.2, 0.9 * norm**exponent))
    return 5.0 if norm == 0.0 else 0.2


class ErrorControl(StepControl):
    """Error control on the embedded estimate of an adaptive method.

    The error of the increments ``(x, v, u, omega, s)`` is measured in the RMS norm scaled by
    ``atol + rtol |value|`` (:meth:`norm`); a step passes when the norm is at most 1, and the next step is
    :func:`step_factor_scalars` times this one.

    Parameters
    ----------
    rtol : float
        Relative tolerance.
    atol : float or ndarray, shape (13,), optional
        Absolute tolerances of the increments; default ``rtol``.
    first_step, max_step : float
        First and largest step (s).
    min_step : float
        The step floor (s): a step that would have to be retaken shorter ends the run with :data:`STEP_FLOOR`
        (:data:`NON_FINITE` when the trial state was not finite; such a trial is retaken at a fifth of its size).
    forced_step : float
        The control shortens no step below this (s): a step of this size (or a shorter first step) that fails
        the tolerance is accepted and counted in :attr:`forced_steps`, for a load that jumps, across which no
        step meets a tolerance set on a smooth error model (docs/numerics.md).  0: none.
    """

    def __init__(
        self,
        rtol: float,
        atol: np.ndarray | float | None = None,
        *,
        first_step: float = 1e-6,
        min_step: float = 1e-10,
        forced_step: float = 0.0,
        max_step: float = math.inf,
    ) -> None:
        self.rtol = _positive("rtol", rtol)
        self.atol = np.broadcast_to(np.asarray(rtol if atol is None else atol, dtype=float), (N_INCREMENTS,))
        self.min_step = _positive("min_step", min_step)
        self.first_step, self.forced_step, self.max_step = first_step, forced_step, max_step
        self._exponent = math.nan

    def start(self, method: Stepper) -> float:
        if not method.adaptive:
            raise ValueError(f"{type(method).__name__} has no error estimate: use a fixed time step")
        self._exponent = -1.0 / (method.error_order + 1)
        # the first step may be shorter than forced_step (a smooth start, e.g. the nose entry)
        return max(min(self.first_step, self.max_step), self.min_step)

    def norm(self, result: StepResult, before: State) -> float:
        after = result.state
        magnitude = np.zeros(N_INCREMENTS)  # the rotation increment starts from zero: absolute tolerance only
        magnitude[POSITION] = np.maximum(np.abs(before.position), np.abs(after.position))
        magnitude[VELOCITY] = np.maximum(np.abs(before.velocity), np.abs(after.velocity))
        magnitude[ANGULAR_VELOCITY] = np.maximum(np.abs(before.angular_velocity), np.abs(after.angular_velocity))
        magnitude[-1] = max(before.path_length, after.path_length)  # the path length, last
        assert result.error is not None  # start() takes adaptive methods only: every step estimates its error
        scaled = result.error / (self.atol + self.rtol * magnitude)
        # np.mean's own arithmetic (a sum, then a division by the count), without its dispatch: once a step
        return float(np.sqrt(np.add.reduce(scaled * scaled) / scaled.size))

    def judge(self, result: StepResult, state: State, size: float) -> tuple[str, float | str]:
        finite = result.state.is_finite()
        norm = self.norm(result, state) if finite else math.inf
        factor = step_factor_scalars(norm, self._exponent)
        if not norm <= 1.0 and (size > self.forced_step or not finite):
            # reject: shorten by the usual factor (a fifth for a non-finite trial)
            shorter = size * min(1.0, factor)
            if finite:
                shorter = max(shorter, self.forced_step)
            if shorter < self.min_step:
                return END, (STEP_FLOOR if finite else NON_FINITE)
            return RETAKE, shorter
        self.forced_steps += norm > 1.0
        return ACCEPT, min(self.max_step, max(self.min_step, self.forced_step, size * factor))


class EnergyGuard:
    """Retakes steps that gain kinetic energy, for loads that can only remove it.

    When the loads only dissipate (``F.V + M.omega <= 0``), a step whose kinetic energy ends above its start by
    more than ``tolerance`` (relative) is a numerical artefact (the overshoot of an explicit step across a jump of
    the load): it is retaken at half its size, down to ``min_step``; a smaller gain is projected away
    (:meth:`project`), so the kinetic energy never increases from one recorded state to the next.

    Attributes
    ----------
    rejections : int
        Steps retaken.
    projections : int
        Accepted states whose gain below the tolerance was removed.
    """

    def __init__(self, min_step: float, tolerance: float = ENERGY_TOLERANCE) -> None:
        self.min_step = _positive("min_step", min_step)
        self.tolerance = tolerance
        self.rejections = self.projections = 0
        self._energies: list[tuple[State, float]] = []  # the last states measured, each with its energy

    def _energy(self, body: RigidBody, state: State) -> float:
        """``body.kinetic_energy(state)``, remembered for the last few states: a step's end state is
        measured by :meth:`judge` and :meth:`project` and is the next step's start."""
        for known, energy in self._energies:
            if known is state:
                return energy
        energy = body.kinetic_energy(state)
        self._energies = [*self._energies[-3:], (state, energy)]
        return energy

    def judge(
        self, body: RigidBody, before: State, after: State, size: float, truncated: bool
    ) -> tuple[str, float | str]:
        """The verdict on an accepted step of ``size``, as :meth:`StepControl.judge`'s; a retake below the floor ends
        the run with :data:`STEP_FLOOR`, or accepts a ``truncated`` step (shortened to end at the time limit)."""
        if self._energy(body, after) > self._energy(body, before) * (1.0 + self.tolerance):
            if 0.5 * size >= self.min_step:
                self.rejections += 1
                return RETAKE, 0.5 * size
            if not truncated:
                return END, STEP_FLOOR  # no shorter step may be taken: the guard cannot hold
        return ACCEPT, size

    def project(self, body: RigidBody, before: State, after: State) -> tuple[State, bool]:
        """``after`` with no more kinetic energy than ``before`` (its velocity and angular velocity scaled by
        ``sqrt(E0 / E1)``: docs/numerics.md, "The energy guard"), and whether it had to be changed."""
        start, end = self._energy(body, before), self._energy(body, after)
        if not end > start:
            return after, False
        self.projections += 1
        scale = math.sqrt(start / end) if end > 0 else 0.0
        for _ in range(4):  # the scaled energy may still exceed the start by an ulp
            projected = replace(after, velocity=after.velocity * scale, angular_velocity=after.angular_velocity * scale)
            if body.kinetic_energy(projected) <= start:
                break
            scale *= 1.0 - 2.0**-52
        return projected, True
