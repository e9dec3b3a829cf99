"""Time integration of a rigid body under a load function, with terminal events.

:func:`simulate` advances a :class:`~dynamics.rigid_body.State` until a terminal event or the time limit.  An
event is a scalar function of the state crossing zero; its time is located to round-off by regula falsi
(:func:`find_root`) on re-taken partial steps from the last accepted state, so nothing is integrated past it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import Any, cast

import numpy as np

from .control import ACCEPT, END, RETAKE, EnergyGuard, StepControl
from .integrators import Evaluation, Stepper, evaluate
from .quaternion import rotation_scalars
from .rigid_body import LoadFunction, RigidBody, State

__all__ = ["Event", "SpeedBelow", "AdvanceEnds", "Trajectory", "simulate", "find_root", "TIME_LIMIT", "MAX_STEPS"]

TIME_LIMIT, MAX_STEPS = "time_limit", "max_steps"


@dataclass(frozen=True)
class Event:
    """A terminal event: ``function(state)`` crossing zero.

    Parameters
    ----------
    name : str
        The end reason reported when the event fires.
    function : callable
        ``function(state) -> float``; continuous in time.
    direction : {1, -1, 0}
        1: fires when the function rises through zero, -1: when it falls, 0: either.
    """

    name: str
    function: Callable[[State], float]
    direction: int = 0

    def fired(self, before: State, after: State, g_before: float, g_after: float) -> bool:
        """Whether the event happens within the step from ``before`` to ``after``."""
        if self.direction >= 0 and g_before < 0.0 <= g_after:
            return True
        return self.direction <= 0 and g_before > 0.0 >= g_after

    def locator(self, before: State) -> Callable[[State], float]:
        """A function of the state whose sign changes at the event inside the step."""
        return self.function

    def step_limit(self, state: State, evaluation: Evaluation) -> float:
        """The longest step (s) from ``state`` (loads ``evaluation``) that can still resolve the event: no limit."""
        return math.inf


class SpeedBelow(Event):
    """The speed falls below ``threshold`` (m/s), or a step carries the velocity through zero and out again.

    Through zero means the velocity reverses (``before . after <= 0``) and the straight line between its values at
    the step's ends passes within ``threshold`` of zero: a step that only turns the velocity by more than 90 degrees
    at speed is no stop.  Inside the step the event is located on the velocity along its direction at the step's
    start.  No step
    reaches past the stop: :meth:`step_limit` is the time the deceleration at its start takes to bring the speed to
    half the threshold (why: docs/numerics.md, "The end of a run").
    """

    threshold: float  # set in __init__ (not a dataclass field: the class is not a dataclass of its own)

    def __init__(self, name: str, threshold: float) -> None:
        super().__init__(name, lambda state: state.speed - threshold, -1)
        object.__setattr__(self, "threshold", threshold)

    def fired(self, before: State, after: State, g_before: float, g_after: float) -> bool:
        if not g_before > 0.0:
            return False
        if g_after <= 0.0:
            return True
        start, change = before.velocity, after.velocity - before.velocity
        if float(start @ after.velocity) > 0.0:
            return False
        # the closest approach to zero of the straight line from the step's first velocity to its last
        share = min(1.0, max(0.0, -float(start @ change) / float(change @ change)))
        return float(np.linalg.norm(start + share * change)) <= self.threshold

    def locator(self, before: State) -> Callable[[State], float]:
        heading = before.velocity / before.speed
        return lambda state: float(state.velocity @ heading) - self.threshold

    def step_limit(self, state: State, evaluation: Evaluation) -> float:
        speed = state.speed
        deceleration = -float(evaluation.acceleration @ state.velocity) / speed if speed > 0.0 else 0.0
        if not deceleration > 0.0 or speed <= self.threshold:
            return math.inf
        return (speed - 0.5 * self.threshold) / deceleration


class AdvanceEnds(Event):
    """The body no longer advances nose first and is slow: its velocity along its axis (body ``x``) is zero or
    negative and its speed at most ``slow`` (m/s).

    The event function is ``max(v . x, |v| - slow)``, continuous, negative exactly in that region; the run ends where
    it falls through zero.  Why a stop: a resistance law acts on the surface that presses into the target, so a body
    that moves back along its own tunnel meets nothing and would drift on with what speed it kept
    (docs/numerics.md, "The end of a run").
    """

    slow: float  # set in __init__ (not a dataclass field: the class is not a dataclass of its own)

    def __init__(self, name: str, slow: float) -> None:
        super().__init__(name, lambda state: max(advance_speed(state), state.speed - slow), -1)
        object.__setattr__(self, "slow", slow)


def advance_speed(state: State) -> float:
    """The velocity of the centre of mass along the body's axis (m/s): positive while it moves nose first."""
    matrix = rotation_scalars(*state.attitude.tolist())  # row by row: the axis is its first column
    vx, vy, vz = state.velocity.tolist()
    return vx * matrix[0] + vy * matrix[3] + vz * matrix[6]


@dataclass
class Trajectory:
    """Recorded states and loads of a run: ``n`` rows, one per accepted step, plus the start."""

    time: np.ndarray  # shape (n,), s
    position: np.ndarray  # shape (n, 3): the centre of mass, world frame (m)
    velocity: np.ndarray  # shape (n, 3): velocity of the centre of mass, world frame (m/s)
    attitude: np.ndarray  # shape (n, 4): unit quaternions, body to world
    angular_velocity: np.ndarray  # shape (n, 3): body frame (rad/s)
    path_length: np.ndarray  # shape (n,): distance travelled by the centre of mass (m)
    force: np.ndarray  # shape (n, 3): load on the body, world frame (N)
    moment: np.ndarray  # shape (n, 3): about the centre of mass, body frame (N m)
    end_reason: str  # name of the event that ended the run, TIME_LIMIT, NON_FINITE, STEP_FLOOR or MAX_STEPS
    # steps, rejected_steps, forced_steps (accepted at the error control's floor with the error above tolerance),
    # energy_rejections, energy_projections, load_evaluations and smallest_step (s; the last step before the time
    # limit not counted)
    statistics: dict[str, Any] = field(default_factory=dict)

    def state(self, index: int = -1) -> State:
        return State(
            float(self.time[index]),
            self.position[index],
            self.velocity[index],
            self.attitude[index],
            self.angular_velocity[index],
            float(self.path_length[index]),
        )


def simulate(
    body: RigidBody,
    loads: LoadFunction,
    initial: State,
    method: Stepper,
    control: StepControl,
    *,
    time_limit: float,
    events: Sequence[Event] = (),
    guard: EnergyGuard | None = None,
    max_steps: int = 5_000_000,
) -> Trajectory:
    """Integrate the motion of ``body`` under ``loads`` from ``initial`` by the Runge-Kutta ``method``.

    The driver only loops: ``control`` sizes and judges every trial step, ``guard`` judges the accepted ones once
    more, and the events end the run; the trajectory holds every accepted step, whatever ended the run.

    Parameters
    ----------
    time_limit : float
        The run ends at this time (s) if no event ends it first.
    events : sequence of Event
        Terminal events, checked after every step.
    guard : EnergyGuard, optional
        For loads that can only remove energy.
    max_steps : int
        Safety limit on the number of steps.
    """
    h = control.start(method)
    state = initial
    first: Evaluation | None  # the evaluation at the start of the next step, if known (StepResult.first)
    first = evaluate(body, loads, state.position, state.velocity, state.attitude, state.angular_velocity)
    calls = 1  # load evaluations: this one, those of every step taken (RETAKEn ones too) and of the event searches
    rows: list[tuple[State, Evaluation]] = [(state, first)]  # the recorded states, each with its evaluation
    values = [event.function(state) for event in events]
    steps = rejected = 0
    end_reason = TIME_LIMIT
    smallest = math.inf

    while (remaining := time_limit - state.time) > 1e-12 * max(1.0, time_limit):
        if steps >= max_steps:
            end_reason = MAX_STEPS
            break
        # no longer than an event can resolve (a stop), and shortened to end at the time limit
        limit = min([h, *(event.step_limit(state, first) for event in events)]) if first is not None else h
        size = min(limit, remaining)
        result = method.step(body, loads, state, size, first)
        calls += result.evaluations
        # a verdict's value: a step size (s) with RETAKE and ACCEPT, an end reason with END
        verdict, value = control.judge(result, state, size)
        next_step = value  # the control's next step, if it and the guard accept
        if verdict == RETAKE:
            rejected += 1
        elif verdict == ACCEPT and guard is not None:
            verdict, value = guard.judge(body, state, result.state, size, truncated=size < limit)
        if verdict == RETAKE:
            h, first = cast(float, value), result.first
            continue
        if verdict == END:
            end_reason = cast(str, value)
            break
        h = cast(float, next_step)
        steps += 1
        if size < remaining:  # the last step before the time limit does not count
            smallest = min(smallest, size)
        new = result.state
        new_values = [event.function(new) for event in events]
        fired = [ev for ev, g0, g1 in zip(events, values, new_values) if ev.fired(state, new, g0, g1)]
        if fired:  # the run ends at the earliest event inside the step
            new, end_reason, searched = _locate(body, loads, method, state, result.first, size, fired)
            calls += searched
        new, projected = guard.project(body, state, new) if guard is not None else (new, False)
        if result.last is not None and not projected and not fired:
            first = result.last
        else:
            first = evaluate(body, loads, new.position, new.velocity, new.attitude, new.angular_velocity)
            calls += 1
        rows.append((new, first))
        if fired:
            break
        state, values = new, new_values

    return Trajectory(
        time=np.array([s.time for s, _ in rows]),
        position=np.array([s.position for s, _ in rows]),
        velocity=np.array([s.velocity for s, _ in rows]),
        attitude=np.array([s.attitude for s, _ in rows]),
        angular_velocity=np.array([s.angular_velocity for s, _ in rows]),
        path_length=np.array([s.path_length for s, _ in rows]),
        force=np.array([e.force for _, e in rows]),
        moment=np.array([e.moment for _, e in rows]),
        end_reason=end_reason,
        statistics={
            "steps": steps,
            "rejected_steps": rejected,
            "forced_steps": int(control.forced_steps),
            "energy_rejections": guard.rejections if guard else 0,
            "energy_projections": guard.projections if guard else 0,
            "load_evaluations": calls,
            "smallest_step": smallest if math.isfinite(smallest) else None,
        },
    )


def find_root(
    function: Callable[[float], float], a: float, b: float, fa: float, fb: float, xtol: float, max_iterations: int = 200
) -> float:
    """A root of ``function`` in ``[a, b]``, where ``fa`` and ``fb`` have opposite signs.

    The Illinois variant of regula falsi, with a bisection step whenever the bracket fails to halve: superlinear
    on smooth functions, never slower than bisection, and the bracket always holds a sign change.  Returns when
    the bracket is narrower than ``xtol``.  (Not scipy's ``brentq``: importing ``scipy.optimize`` costs a short
    run much of its wall time.)
    """
    if not (fa < 0.0 < fb or fb < 0.0 < fa):
        raise ValueError(f"no sign change on [{a}, {b}]: f = {fa}, {fb}")
    side = 0
    for _ in range(max_iterations):
        width = b - a
        if width <= xtol:
            break
        x = b - fb * width / (fb - fa)
        if not a < x < b:
            x = 0.5 * (a + b)
        fx = function(x)
        if fx == 0.0:
            return x
        if (fx < 0.0) == (fb < 0.0):
            b, fb = x, fx
            if side == -1:
                fa *= 0.5  # Illinois: the end that stayed twice is weighted down
            side = -1
        else:
            a, fa = x, fx
            if side == 1:
                fb *= 0.5
            side = 1
        if b - a > 0.5 * width:
            x = 0.5 * (a + b)  # slow progress: bisect once
            fx = function(x)
            if fx == 0.0:
                return x
            if (fx < 0.0) == (fb < 0.0):
                b, fb = x, fx
            else:
                a, fa = x, fx
            side = 0
    return 0.5 * (a + b)


def _locate(
    body: RigidBody,
    loads: LoadFunction,
    method: Stepper,
    state: State,
    first: Evaluation | None,
    size: float,
    events: list[Event],
) -> tuple[State, str, int]:
    """The earliest of ``events`` inside a step of ``size`` from ``state``, and the load evaluations it took.

    Each event's locator changes sign inside the step; :func:`find_root` finds the root on re-taken partial
    steps, and the end state is taken just past it, on the side where the event has happened.
    """
    calls = 0

    def partial_step(s: float) -> State:
        nonlocal calls
        result = method.step(body, loads, state, s, first)
        calls += result.evaluations
        return result.state

    tolerance = max(1e-15, 1e-12 * size)

    def crossing(event: Event) -> float:
        locator = event.locator(state)
        g_start = locator(state)

        def g(s: float) -> float:
            return g_start if s <= 0.0 else locator(partial_step(s))

        g_end = g(size)
        if g_end == 0.0 or (g_start > 0) == (g_end > 0):
            return size  # no sign change to refine: the event is at the end of the step
        t_cross = find_root(g, 0.0, size, g_start, g_end, tolerance)
        return min(size, t_cross + tolerance) if (g(t_cross) > 0) == (g_start > 0) else t_cross

    t_cross, event = min(((crossing(event), event) for event in events), key=lambda pair: pair[0])
    return partial_step(t_cross), event.name, calls
