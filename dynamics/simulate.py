"""Time integration of a rigid body under a load function, with terminal events.

:func:`simulate` advances a :class:`~dynamics.rigid_body.State` with a fixed
step (any method) or with error control (methods with an embedded pair) until
a terminal event or the time limit.  An event is a scalar function of the
state crossing zero in a given direction; its time is located to round-off by
regula falsi (:func:`find_root`) on re-taken partial steps from the last accepted state, so the
run ends exactly at the event and nothing is integrated past it.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field, replace

import numpy as np

from .integrators import Evaluation, RungeKutta, StepResult, evaluate
from .rigid_body import LoadFunction, RigidBody, State

__all__ = ["Event", "SpeedBelow", "Trajectory", "simulate", "find_root", "TIME_LIMIT", "NON_FINITE", "MAX_STEPS",
           "STEP_FLOOR"]

TIME_LIMIT, NON_FINITE, MAX_STEPS = "time_limit", "non_finite", "max_steps"
# the integration needed a step shorter than its floor: a numerical failure, the history up to it is kept
STEP_FLOOR = "step_floor"

# relative kinetic-energy gain above which a step of a dissipative system is retaken: far above
# round-off and the harmless gains of the shank's sliding chatter (1e-10 after convergence, up to 5e-8
# while a turned projectile leaves the target),
# far below the pumping that lets a run creep near rest (percent per step)
ENERGY_TOLERANCE = 1e-7


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


class SpeedBelow(Event):
    """The speed falls below ``threshold`` (m/s).

    A step may also carry the velocity through zero and out again without
    ending below the threshold (a discrete overshoot of a body brought to
    rest); such a reversal fires too.  Inside the step the event is located on
    the velocity component along the velocity at the start of the step, which
    passes through the threshold in both cases.
    """

    def __init__(self, name: str, threshold: float) -> None:
        super().__init__(name, lambda state: state.speed - threshold, -1)
        object.__setattr__(self, "threshold", threshold)

    def fired(self, before: State, after: State, g_before: float, g_after: float) -> bool:
        reversed_ = float(before.velocity @ after.velocity) <= 0.0
        return g_before > 0.0 and (g_after <= 0.0 or reversed_)

    def locator(self, before: State) -> Callable[[State], float]:
        heading = before.velocity / before.speed
        return lambda state: float(state.velocity @ heading) - self.threshold


@dataclass
class Trajectory:
    """Recorded states and loads of a run (one row per accepted step, plus the start).

    Attributes
    ----------
    time : ndarray, shape (n,)
    position, velocity : ndarray, shape (n, 3)
        Centre of mass, world frame (m, m/s).
    attitude : ndarray, shape (n, 4)
        Unit quaternions, body to world.
    angular_velocity : ndarray, shape (n, 3)
        Body frame (rad/s).
    path_length : ndarray, shape (n,)
        Distance travelled by the centre of mass (m).
    force : ndarray, shape (n, 3)
        Load on the body, world frame (N).
    moment : ndarray, shape (n, 3)
        Moment about the centre of mass, body frame (N m).
    end_reason : str
        Name of the event that ended the run, ``time_limit``, ``non_finite`` or ``max_steps``.
    statistics : dict
        ``steps``, ``rejected_steps``, ``forced_steps`` (accepted at the
        error control's floor with the error above tolerance),
        ``energy_rejections``, ``energy_projections``, ``load_evaluations`` and
        ``smallest_step`` (s; the last step before the time limit not counted).
    """

    time: np.ndarray
    position: np.ndarray
    velocity: np.ndarray
    attitude: np.ndarray
    angular_velocity: np.ndarray
    path_length: np.ndarray
    force: np.ndarray
    moment: np.ndarray
    end_reason: str
    statistics: dict = field(default_factory=dict)

    def state(self, index: int = -1) -> State:
        return State(float(self.time[index]), self.position[index], self.velocity[index],
                     self.attitude[index], self.angular_velocity[index], float(self.path_length[index]))


class _Recorder:
    def __init__(self) -> None:
        self.rows: list[tuple[State, Evaluation]] = []

    def add(self, state: State, evaluation: Evaluation) -> None:
        self.rows.append((state, evaluation))

    def trajectory(self, end_reason: str, statistics: dict) -> Trajectory:
        states = [s for s, _ in self.rows]
        evals = [e for _, e in self.rows]
        return Trajectory(
            time=np.array([s.time for s in states]),
            position=np.array([s.position for s in states]),
            velocity=np.array([s.velocity for s in states]),
            attitude=np.array([s.attitude for s in states]),
            angular_velocity=np.array([s.angular_velocity for s in states]),
            path_length=np.array([s.path_length for s in states]),
            force=np.array([e.force for e in evals]),
            moment=np.array([e.moment for e in evals]),
            end_reason=end_reason,
            statistics=statistics,
        )


def _error_norm(result: StepResult, before: State, rtol: float, atol: np.ndarray) -> float:
    """RMS of the error estimate scaled by ``atol + rtol |value|``."""
    after = result.state
    magnitude = np.concatenate([
        np.maximum(np.abs(before.position), np.abs(after.position)),
        np.maximum(np.abs(before.velocity), np.abs(after.velocity)),
        np.zeros(3),  # the rotation increment starts from zero: absolute tolerance only
        np.maximum(np.abs(before.angular_velocity), np.abs(after.angular_velocity)),
        [max(before.path_length, after.path_length)],
    ])
    scaled = result.error / (atol + rtol * magnitude)
    return float(np.sqrt(np.mean(scaled * scaled)))


def simulate(body: RigidBody, loads: LoadFunction, initial: State, method: RungeKutta, *,
             time_limit: float, time_step: float | None = None, rtol: float | None = None,
             atol: np.ndarray | float | None = None, first_step: float = 1e-6,
             min_step: float = 1e-10, forced_step: float = 0.0, max_step: float = math.inf,
             events: Sequence[Event] = (), max_steps: int = 5_000_000,
             dissipative: bool = False) -> Trajectory:
    """Integrate the motion of ``body`` under ``loads`` from ``initial``.

    Parameters
    ----------
    body : RigidBody
        Mass and inertia.
    loads : LoadFunction
        Resultant force (world) and moment (body) for a state.
    initial : State
        The start.
    method : RungeKutta
        The Runge-Kutta method.
    time_limit : float
        The run ends at this time (s) if no event ends it first.
    time_step : float, optional
        Fixed step (s).  Give either this or ``rtol``.
    rtol : float, optional
        Relative tolerance of the error control (needs an adaptive method).
    atol : float or ndarray, shape (13,), optional
        Absolute tolerance of the increments ``(x, v, u, omega, s)``; default ``rtol``.
    first_step, max_step : float
        First and largest step of the error control (s).
    min_step : float
        The step floor (s): no step is retaken shorter than this.  When a step
        would have to be (the error control rejects a step and
        ``forced_step`` does not apply, or the energy guard rejects a step of
        less than twice the floor) the run ends with :data:`STEP_FLOOR`; an
        error-controlled trial step whose state is not finite is retaken
        shorter, and at the floor the run ends with :data:`NON_FINITE`.  The
        history up to the last accepted step is kept.  The last step before the
        time limit may be shorter than the floor.
    forced_step : float
        Error control only: the error control does not shorten a step below
        this (s); a step of this size (or a shorter first step) that fails the
        tolerance is accepted and counted in ``statistics["forced_steps"]``.  The DAFL load jumps (at
        ``Vn = 0`` on the shank, where points cross the target surface), and
        across a jump no step size meets a tolerance set on a smooth error
        model: without this bound the step collapses at every jump and the
        cost has no bound.  0 (default): no forced steps.
    events : sequence of Event
        Terminal events, checked after every step.
    max_steps : int
        Safety limit on the number of steps.
    dissipative : bool
        The loads can only remove energy (``F.V + M.omega <= 0``), so a step
        whose kinetic energy ends above its start (by more than
        :data:`ENERGY_TOLERANCE`, relative) is a numerical artefact: an explicit step across a jump of the load
        overshoots, and repeated overshoots (chatter) can pump energy in.
        Such a step is retaken at half the size, down to ``min_step``; the
        retakes are counted in ``statistics["energy_rejections"]``.  A smaller
        gain is projected away (:func:`_no_energy_gain`, counted in
        ``statistics["energy_projections"]``), so the kinetic energy never
        increases from one recorded state to the next.

    Returns
    -------
    Trajectory
        One row per accepted step, plus the start; ``end_reason`` is the name
        of the event that ended the run, :data:`TIME_LIMIT`, :data:`NON_FINITE`,
        :data:`STEP_FLOOR` or :data:`MAX_STEPS`.
    """
    if (time_step is None) == (rtol is None):
        raise ValueError("give exactly one of time_step (fixed step) and rtol (error control)")
    if rtol is not None and not method.adaptive:
        raise ValueError(f"{type(method).__name__} has no error estimate: use a fixed time_step")
    if time_step is not None and not time_step > 0:
        raise ValueError(f"time_step = {time_step}: must be > 0")
    if not (min_step > 0 and math.isfinite(min_step)):
        raise ValueError(f"min_step = {min_step}: must be a finite number > 0")
    if rtol is not None:
        atol = np.broadcast_to(np.asarray(rtol if atol is None else atol, dtype=float), (13,))

    calls = 0

    def counted(*args):
        nonlocal calls
        calls += 1
        return loads(*args)

    state = initial
    first = evaluate(body, counted, state.position, state.velocity, state.attitude,
                     state.angular_velocity)
    recorder = _Recorder()
    recorder.add(state, first)
    values = [event.function(state) for event in events]
    steps = rejected = forced = energy_rejections = projections = 0
    # the first step may be shorter than forced_step (a smooth start, e.g. the nose entry); the error
    # control then grows it, and shortens no step below forced_step
    h = time_step if time_step is not None else max(min(first_step, max_step), min_step)
    end_reason = TIME_LIMIT
    smallest = math.inf

    while True:
        remaining = time_limit - state.time
        if remaining <= 1e-12 * max(1.0, time_limit):
            break
        if steps >= max_steps:
            end_reason = MAX_STEPS
            break
        size = min(h, remaining)
        result = method.step(body, counted, state, size, first)
        new = result.state
        finite = new.is_finite()
        if rtol is not None:
            norm = _error_norm(result, state, rtol, atol) if finite else math.inf
            if not norm <= 1.0 and (size > forced_step or not finite):
                # reject: shorten by the usual factor (a fifth for a non-finite trial)
                factor = 0.9 * norm ** (-1.0 / (method.error_order + 1)) if math.isfinite(norm) else 0.2
                shorter = size * min(1.0, max(0.2, factor))
                if finite:
                    shorter = max(shorter, forced_step)
                if shorter < min_step:
                    end_reason = STEP_FLOOR if finite else NON_FINITE
                    break
                rejected += 1
                h = shorter
                first = result.first
                continue
            forced += norm > 1.0
            factor = 0.9 * norm ** (-1.0 / (method.error_order + 1)) if norm > 0 else 5.0
            h = min(max_step, max(min_step, forced_step, size * min(5.0, max(0.2, factor))))
        if not finite:
            end_reason = NON_FINITE
            break
        if dissipative:
            before, after = body.kinetic_energy(state), body.kinetic_energy(new)
            if after > before * (1.0 + ENERGY_TOLERANCE):
                if 0.5 * size >= min_step:
                    energy_rejections += 1
                    h = 0.5 * size
                    first = result.first
                    continue
                if size >= h:
                    end_reason = STEP_FLOOR  # no shorter step may be taken: the guard cannot hold
                    break
                # else: a last step before the time limit, already shorter than the floor: accepted
            if time_step is not None:
                h = time_step
        steps += 1
        if size < remaining:  # the last step before the time limit does not count
            smallest = min(smallest, size)
        new_values = [event.function(new) for event in events]
        fired = [ev for ev, g0, g1 in zip(events, values, new_values) if ev.fired(state, new, g0, g1)]
        if fired:
            new, end_reason = _locate(body, counted, method, state, result.first, size, fired)
            if dissipative:
                new, projected = _no_energy_gain(body, state, new)
                projections += projected
            last = evaluate(body, counted, new.position, new.velocity, new.attitude,
                            new.angular_velocity)
            recorder.add(new, last)
            break
        projected = False
        if dissipative:
            new, projected = _no_energy_gain(body, state, new)
            projections += projected
        first = result.last if result.last is not None and not projected else evaluate(
            body, counted, new.position, new.velocity, new.attitude, new.angular_velocity)
        recorder.add(new, first)
        state, values = new, new_values

    statistics = {"steps": steps, "rejected_steps": rejected, "forced_steps": int(forced),
                  "energy_rejections": energy_rejections, "energy_projections": projections,
                  "load_evaluations": calls,
                  "smallest_step": smallest if math.isfinite(smallest) else None}
    return recorder.trajectory(end_reason, statistics)


def _no_energy_gain(body: RigidBody, before: State, after: State) -> tuple[State, bool]:
    """``after`` with no more kinetic energy than ``before``, and whether it had to be changed.

    A step of a dissipative system that gains less than :data:`ENERGY_TOLERANCE`
    (round-off, or the overshoot of an explicit step across the shank's
    ``Vn = 0`` switch: up to 3e-8 while projectile #3 turns and leaves the
    target) is not retaken: its velocity and angular velocity are scaled by
    ``sqrt(E0 / E1)``, which keeps their directions and removes the gain, as
    the unit quaternion is renormalised after every step.  The change is below
    the tolerance the guard already accepts, and the kinetic energy never increases.
    """
    start, end = body.kinetic_energy(before), body.kinetic_energy(after)
    if not end > start:
        return after, False
    scale = math.sqrt(start / end) if end > 0 else 0.0
    for _ in range(4):  # the scaled energy may still exceed the start by an ulp
        projected = replace(after, velocity=after.velocity * scale, angular_velocity=after.angular_velocity * scale)
        if body.kinetic_energy(projected) <= start:
            break
        scale *= 1.0 - 2.0 ** -52
    return projected, True


def find_root(function: Callable[[float], float], a: float, b: float, fa: float, fb: float,
              xtol: float, max_iterations: int = 200) -> float:
    """A root of ``function`` in ``[a, b]``, where ``fa`` and ``fb`` have opposite signs.

    The Illinois variant of regula falsi, with a bisection step whenever the
    bracket fails to halve: superlinear on smooth functions, never slower than
    bisection, and the bracket always holds a sign change.  Returns when the
    bracket is narrower than ``xtol``.  (scipy's ``brentq`` would do, but
    importing ``scipy.optimize`` costs about 0.4 s, the better half of a short
    run's wall time, and every run ends with an event.)
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


def _locate(body: RigidBody, loads: LoadFunction, method: RungeKutta, state: State,
            first: Evaluation, size: float, events: list[Event]) -> tuple[State, str]:
    """The earliest of ``events`` inside a step of ``size`` from ``state``.

    Each event's locator changes sign inside the step; regula falsi finds
    the root on re-taken partial steps, and the end state is taken just past
    it, on the side where the event has happened.
    """
    best: tuple[float, Event] | None = None
    tolerance = max(1e-15, 1e-12 * size)
    for event in events:
        locator = event.locator(state)
        g_start = locator(state)

        def g(s: float, locator=locator, g_start=g_start) -> float:
            return g_start if s <= 0.0 else locator(method.step(body, loads, state, s, first).state)

        g_end = g(size)
        if g_end == 0.0 or (g_start > 0) == (g_end > 0):
            t_cross = size  # no sign change to refine: the event is at the end of the step
        else:
            t_cross = find_root(g, 0.0, size, g_start, g_end, tolerance)
            if (g(t_cross) > 0) == (g_start > 0):
                t_cross = min(size, t_cross + tolerance)
        if best is None or t_cross < best[0]:
            best = (t_cross, event)
    assert best is not None
    t_cross, event = best
    return method.step(body, loads, state, t_cross, first).state, event.name
