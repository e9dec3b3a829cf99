"""Integrators, step control, the energy guard and events, each problem paired with its exact solution."""

import math

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from dynamics import (
    NON_FINITE,
    RK4,
    STEP_FLOOR,
    TIME_LIMIT,
    AdvanceEnds,
    DormandPrince54,
    EnergyGuard,
    ErrorControl,
    Event,
    FixedStep,
    RigidBody,
    SpeedBelow,
    State,
    simulate,
)
from dynamics.quaternion import exp_map, from_rotation_matrix, multiply, rotation_matrices, rotation_matrix

I_AXIAL, I_TRANSVERSE = 0.25, 2.3
BODY = RigidBody(75.0, np.diag([I_AXIAL, I_TRANSVERSE, I_TRANSVERSE]))
NO_LOAD = lambda x, v, r, w: (np.zeros(3), np.zeros(3))  # noqa: E731


def _spinning_start():
    r0 = Rotation.from_rotvec([0.3, -0.5, 0.2]).as_matrix()
    return State(0.0, np.zeros(3), np.array([1.0, 2.0, 3.0]), from_rotation_matrix(r0), np.array([40.0, 3.0, -2.0]))


def _torque_free_exact(start: State, t: float) -> np.ndarray:
    """R(t) = exp(t L/I_t) R0 exp(t lambda e_x), lambda = w_x (1 - I_a/I_t), axisymmetric body."""
    r0 = rotation_matrix(start.attitude)
    w = start.angular_velocity
    momentum_world = r0 @ (BODY.inertia @ w)
    lam = w[0] * (1 - I_AXIAL / I_TRANSVERSE)
    return (
        Rotation.from_rotvec(t * momentum_world / I_TRANSVERSE).as_matrix()
        @ r0
        @ Rotation.from_rotvec([t * lam, 0, 0]).as_matrix()
    )


def _attitude_error(h: float, method=RK4, **kw) -> float:
    start = _spinning_start()
    tr = simulate(BODY, NO_LOAD, start, method(), FixedStep(h), time_limit=0.5, **kw)
    return float(np.abs(rotation_matrix(tr.attitude[-1]) - _torque_free_exact(start, 0.5)).max())


def test_rk4_attitude_converges_at_fourth_order():
    errors = [_attitude_error(h) for h in (4e-3, 2e-3, 1e-3)]
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((rates > 3.7) & (rates < 4.3)), rates


def test_dopri54_meets_its_tolerance_on_the_free_top():
    start = _spinning_start()
    for rtol in (1e-6, 1e-9):
        tr = simulate(BODY, NO_LOAD, start, DormandPrince54(), ErrorControl(rtol), time_limit=0.5)
        error = np.abs(rotation_matrix(tr.attitude[-1]) - _torque_free_exact(start, 0.5)).max()
        assert error < 100 * rtol
        assert tr.time[-1] == pytest.approx(0.5, abs=1e-15)


def test_unit_quaternion_and_momentum_over_a_long_run():
    """5 s of a fast spin (10^4 steps): |q| stays 1; the momentum drift is RK4's O(h^4)."""
    start = _spinning_start()
    drifts = []
    for h in (1e-3, 5e-4):
        tr = simulate(BODY, NO_LOAD, start, RK4(), FixedStep(h), time_limit=5.0)
        assert np.abs(np.linalg.norm(tr.attitude, axis=1) - 1).max() < 1e-12
        momentum = np.array([rotation_matrix(q) @ (BODY.inertia @ w) for q, w in zip(tr.attitude, tr.angular_velocity)])
        drifts.append(np.abs(momentum - momentum[0]).max())
    assert 3.7 < math.log2(drifts[0] / drifts[1]) < 4.3


def test_constant_force_parabola_and_located_stop():
    """Constant braking force: v = v0 - (F/m) t, exact for RK4; the stop is located to round-off."""
    v0, brake, stop = 300.0, 2.0e5, 0.5
    direction = np.array([0.6, 0.0, -0.8])
    force = -brake * direction
    loads = lambda x, v, r, w: (force, np.zeros(3))  # noqa: E731
    start = State(0.0, np.zeros(3), v0 * direction, np.array([1.0, 0, 0, 0]), np.zeros(3))
    stopped = SpeedBelow("stopped", stop)
    # a 7e-4 s step changes the velocity by 1.9 m/s: the speed passes through zero
    # and out again inside one step, and the reversal must still end the run
    tr = simulate(BODY, loads, start, RK4(), FixedStep(7e-4), time_limit=1.0, events=[stopped])
    t_stop = (v0 - stop) * BODY.mass / brake
    assert tr.end_reason == "stopped"
    assert tr.time[-1] == pytest.approx(t_stop, rel=1e-12)
    expected = v0 * t_stop - 0.5 * brake / BODY.mass * t_stop**2
    assert tr.path_length[-1] == pytest.approx(expected, rel=1e-10)
    np.testing.assert_allclose(tr.position[-1], expected * direction, rtol=1e-10)
    assert np.all(np.diff(tr.time) > 0) and tr.time[-2] < t_stop


@pytest.mark.parametrize("method", [RK4, DormandPrince54])
@pytest.mark.parametrize("step", [1e-4, 1e-3, 1e-2])
def test_dry_friction_stops_at_its_exact_place_whatever_the_step(method, step):
    """A braking force that reverses with the velocity (a static strength, dry friction): ``F = -F_s v/|v|``.
    The body stops at ``t = m v0 / F_s`` after ``m v0^2 / (2 F_s)``.  Steps far longer than the stopping
    time would let the stages see the body moving both ways and the forces cancel (the body creeps on); a
    step may not reach past the stop, so the run ends where the exact solution reaches the stop speed."""
    v0, brake, stop = 20.0, 3.0e5, 0.5
    direction = np.array([0.0, 0.6, -0.8])

    def loads(x, v, r, w):
        speed = float(np.linalg.norm(v))
        return (-brake * v / speed if speed > 0 else np.zeros(3)), np.zeros(3)

    start = State(0.0, np.zeros(3), v0 * direction, np.array([1.0, 0, 0, 0]), np.zeros(3))
    control = FixedStep(step) if method is RK4 else ErrorControl(1e-6, first_step=step)
    tr = simulate(BODY, loads, start, method(), control, time_limit=1.0, events=[SpeedBelow("stopped", stop)])
    deceleration = brake / BODY.mass
    assert tr.end_reason == "stopped"
    assert tr.time[-1] == pytest.approx((v0 - stop) / deceleration, rel=1e-9)
    assert tr.path_length[-1] == pytest.approx((v0**2 - stop**2) / (2 * deceleration), rel=1e-9)
    assert len(tr.time) <= max(30, (v0 - stop) / deceleration / step + 3)  # no creeping


@pytest.mark.parametrize("method", [RK4, DormandPrince54])
@pytest.mark.parametrize("slow", [3.0, 1.5])
def test_advance_ends_where_the_body_stops_moving_nose_first_while_slow(method, slow):
    """A constant force against the axis of a turned body that also drifts sideways at 2 m/s: the velocity along the
    axis is ``v0 - a t`` and the speed ``sqrt((v0 - a t)^2 + 2^2)``.  The advance ends at ``t = v0 / a``, where the
    speed is 2 m/s: with ``slow`` = 3 m/s the run ends there, exactly; with ``slow`` = 1.5 m/s the body is never that
    slow and runs to the time limit (the sideways drift keeps it above the stop speed too)."""
    v0, deceleration, drift = 40.0, 2.0e3, 2.0
    attitude = from_rotation_matrix(Rotation.from_rotvec([0.2, -0.7, 0.4]).as_matrix())
    axis, side = rotation_matrix(attitude)[:, 0], rotation_matrix(attitude)[:, 1]
    force = -BODY.mass * deceleration * axis
    loads = lambda x, v, r, w: (force, np.zeros(3))  # noqa: E731
    start = State(0.0, np.zeros(3), v0 * axis + drift * side, attitude, np.zeros(3))
    control = FixedStep(7e-4) if method is RK4 else ErrorControl(1e-8, first_step=1e-4)
    events = [SpeedBelow("stopped", 0.5), AdvanceEnds("advance ends", slow)]
    tr = simulate(BODY, loads, start, method(), control, time_limit=0.05, events=events)
    if slow > drift:
        assert tr.end_reason == "advance ends"
        assert tr.time[-1] == pytest.approx(v0 / deceleration, rel=1e-10)
        assert float(tr.velocity[-1] @ axis) == pytest.approx(0.0, abs=1e-8)
    else:
        assert tr.end_reason == TIME_LIMIT
        assert float(tr.velocity[-1] @ axis) < 0.0


def test_rising_event_is_located():
    """A body thrown upward at 30 m/s under 9.81 m/s^2 reaches Z = 20 m at t = (30 - sqrt(900 - 392.4))/9.81."""
    g = np.array([0.0, 0.0, -9.81 * BODY.mass])
    start = State(0.0, np.zeros(3), np.array([0.0, 0.0, 30.0]), np.array([1.0, 0, 0, 0]), np.zeros(3))
    height = Event("height", lambda s: s.position[2] - 20.0, direction=1)
    tr = simulate(
        BODY, lambda x, v, r, w: (g, np.zeros(3)), start, RK4(), FixedStep(0.1), time_limit=5.0, events=[height]
    )
    assert tr.end_reason == "height"
    assert tr.time[-1] == pytest.approx((30 - math.sqrt(900 - 392.4)) / 9.81, rel=1e-12)


def test_time_limit_is_hit_exactly():
    tr = simulate(BODY, NO_LOAD, _spinning_start(), RK4(), FixedStep(3e-3), time_limit=0.01)
    assert tr.end_reason == TIME_LIMIT and tr.time[-1] == pytest.approx(0.01, abs=1e-15)
    assert len(tr.time) == 5  # 0, 3, 6, 9, 10 ms


def test_non_finite_load_ends_the_run_and_keeps_the_history():
    calls = {"n": 0}

    def failing(x, v, r, w):
        calls["n"] += 1
        return (np.full(3, np.nan) if calls["n"] > 9 else np.zeros(3)), np.zeros(3)

    tr = simulate(BODY, failing, _spinning_start(), RK4(), FixedStep(1e-3), time_limit=1.0)
    assert tr.end_reason == NON_FINITE
    assert len(tr.time) == 3 and np.isfinite(tr.position).all()


def test_bad_integrator_settings():
    with pytest.raises(ValueError, match="time_step = -1"):
        FixedStep(-1.0)
    with pytest.raises(ValueError, match="min_step = 0"):
        ErrorControl(1e-6, min_step=0.0)
    with pytest.raises(ValueError, match="no error estimate"):
        simulate(BODY, NO_LOAD, _spinning_start(), RK4(), ErrorControl(1e-6), time_limit=1.0)


def _pumping(gain: float):
    """A load that adds ``gain`` (relative) kinetic energy per second along the velocity: no dissipative system."""

    def loads(x, v, r, w):
        return 0.5 * gain * BODY.mass * v, np.zeros(3)

    return loads


def _energies(tr) -> np.ndarray:
    return np.array([BODY.kinetic_energy(tr.state(i)) for i in range(len(tr.time))])


def test_energy_guard_projects_small_gains_and_the_energy_never_rises():
    """A gain of 1e-9 per 1e-3 s step is below the guard's tolerance: every step is kept, its gain removed."""
    start = State(0.0, np.zeros(3), np.array([100.0, 0.0, 0.0]), np.array([1.0, 0, 0, 0]), np.array([0, 1.0, 0]))
    guard = EnergyGuard(min_step=1e-6)
    tr = simulate(BODY, _pumping(1e-6), start, RK4(), FixedStep(1e-3), time_limit=0.01, guard=guard)
    assert tr.end_reason == TIME_LIMIT and tr.statistics["energy_rejections"] == 0
    assert tr.statistics["energy_projections"] == guard.projections == 10
    assert np.all(np.diff(_energies(tr)) <= 0.0)
    free = simulate(BODY, _pumping(1e-6), start, RK4(), FixedStep(1e-3), time_limit=0.01)
    assert np.all(np.diff(_energies(free)) > 0.0)  # the same load without the guard gains


def test_energy_guard_retakes_large_gains_down_to_its_floor():
    """A gain of 1e-2 per second: every halving still gains above 1e-7, so the run ends at the step floor."""
    start = State(0.0, np.zeros(3), np.array([100.0, 0.0, 0.0]), np.array([1.0, 0, 0, 0]), np.zeros(3))
    tr = simulate(
        BODY, _pumping(1.0), start, RK4(), FixedStep(1e-3), time_limit=0.01, guard=EnergyGuard(min_step=1e-3 / 1024)
    )
    assert tr.end_reason == STEP_FLOOR and len(tr.time) == 1  # the history up to the failure: the start
    assert tr.statistics["energy_rejections"] == 10  # 1e-3 halved ten times reaches the floor


def test_error_control_forces_steps_at_its_minimum():
    """A load that jumps every 1e-4 s: no step meets 1e-10; at forced_step each is accepted and counted."""

    def jumping(x, v, r, w):
        return np.array([0.0, 1e5 * (-1) ** int(x[0] / 1e-2), 0.0]), np.zeros(3)

    start = State(0.0, np.zeros(3), np.array([100.0, 0.0, 0.0]), np.array([1.0, 0, 0, 0]), np.zeros(3))
    control = ErrorControl(1e-10, first_step=1e-6, forced_step=1e-5, min_step=1e-8)
    tr = simulate(BODY, jumping, start, DormandPrince54(), control, time_limit=2e-3)
    assert tr.end_reason == TIME_LIMIT
    assert tr.statistics["forced_steps"] == control.forced_steps > 0
    assert tr.statistics["smallest_step"] >= 1e-6 * (1 - 1e-12)
    no_floor = simulate(
        BODY, jumping, start, DormandPrince54(), ErrorControl(1e-10, first_step=1e-6, min_step=1e-8), time_limit=2e-3
    )
    assert no_floor.end_reason == STEP_FLOOR  # without forced steps the control shortens to its floor


def test_quaternion_helpers_agree_with_scipy():
    rng = np.random.default_rng(0)
    for _ in range(20):
        v = rng.normal(size=3)
        q = exp_map(v)
        expected = Rotation.from_rotvec(v).as_matrix()
        np.testing.assert_allclose(rotation_matrix(q), expected, atol=1e-14)
        np.testing.assert_allclose(rotation_matrix(from_rotation_matrix(expected)), expected, atol=1e-14)
        w = rng.normal(size=3)
        np.testing.assert_allclose(
            rotation_matrix(multiply(exp_map(v), exp_map(w))),
            expected @ Rotation.from_rotvec(w).as_matrix(),
            atol=1e-13,
        )
    assert np.allclose(exp_map(np.array([1e-12, 0, 0])), [1, 5e-13, 0, 0])
    assert math.isclose(np.linalg.norm(exp_map(np.array([3.0, 4.0, 0.0]))), 1.0)


def test_the_array_form_gives_each_rotation_matrix_to_the_bit():
    """``rotation_matrices`` over any leading shape is ``rotation_matrix`` of each quaternion, bit for bit (the run's
    history and the reduced model's starts use it)."""
    rng = np.random.default_rng(3)
    q = rng.normal(size=(2, 50, 4))
    q /= np.linalg.norm(q, axis=-1, keepdims=True)
    q[0, :5, 1:] = 0.0  # the identity's neighbours: exact zeros off the diagonal
    matrices = rotation_matrices(q)
    assert matrices.shape == (2, 50, 3, 3)
    assert np.array_equal(matrices, [[rotation_matrix(p) for p in row] for row in q])
    assert np.array_equal(rotation_matrices(q[1, 7]), rotation_matrix(q[1, 7]))


@pytest.mark.parametrize(
    ("function", "a", "b"),
    [
        (math.cos, 0.0, 3.0),  # smooth: pi/2
        (lambda x: x**3 - 2.0 * x - 5.0, 2.0, 3.0),  # Newton's cubic
        (lambda x: math.exp(x) - 1e6, 0.0, 30.0),  # very convex: regula falsi stalls without Illinois
        (lambda x: -1.0 if x < 0.3 else 1.0, 0.0, 1.0),  # a jump: only bisection converges
    ],
)
def test_find_root_agrees_with_brentq(function, a, b):
    from scipy.optimize import brentq

    from dynamics.simulate import find_root

    calls = 0

    def counted(x):
        nonlocal calls
        calls += 1
        return function(x)

    root = find_root(counted, a, b, function(a), function(b), xtol=1e-13)
    assert root == pytest.approx(brentq(function, a, b, xtol=1e-14), abs=2e-13)
    assert calls <= 2 * math.ceil(math.log2((b - a) / 1e-13)) + 2  # never much worse than bisection


def test_find_root_needs_a_sign_change():
    from dynamics.simulate import find_root

    with pytest.raises(ValueError, match="no sign change"):
        find_root(math.cos, 0.0, 1.0, 1.0, math.cos(1.0), 1e-12)
