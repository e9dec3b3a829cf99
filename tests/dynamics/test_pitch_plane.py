"""The compiled pitch-plane driver (dynamics.pitch_plane) on problems with exact solutions, and its events."""

import math

import numpy as np
import pytest
from numba import njit

from dynamics.pitch_plane import (
    CONVERGED,
    EXITED,
    OUTCOME_FIELDS,
    STOPPED,
    TIME_LIMIT,
    TURNED,
    PlaneBody,
    PlaneEnds,
    PlaneSteps,
    trajectory,
)

CONSTANT_MOMENT, LINEAR_DRAG, PENDULUM = 0.0, 1.0, 2.0
MASS, INERTIA = 2.0, 0.5
MAX_STEP = 1e-3  # s: events are not located, so a run ends within a step of one


@njit(cache=True)
def _load(data, height, sin_theta, cos_theta, vx, vz, q, out):
    """data[0] picks the load: a constant moment data[1]; a drag -data[1] v; a pendulum's data[1] sin(phi)
    (the body's ``cos theta``), which swings the axis angle ``phi`` about 0."""
    out[0] = out[1] = out[2] = 0.0
    if data[0] == CONSTANT_MOMENT:
        out[2] = data[1]
    elif data[0] == LINEAR_DRAG:
        out[0], out[1] = -data[1] * vx, -data[1] * vz
    else:
        out[2] = data[1] * cos_theta


@njit(cache=True)
def _lowest(data, height, sin_theta, cos_theta):
    return height  # a point body


@njit(cache=True)
def _run(data, y0, gravity, rtol, time_limit, turn_limit, threshold, stop_when_converged):
    return trajectory(
        _load,
        _lowest,
        data,
        y0,
        PlaneBody(MASS, INERTIA, gravity),
        PlaneSteps(rtol, np.ones(6), 1e-4, MAX_STEP),
        PlaneEnds(1e-3, time_limit, turn_limit, threshold, 0.0, stop_when_converged),
    )


def run(
    kind,
    value,
    y0,
    gravity=0.0,
    rtol=1e-8,
    time_limit=1.0,
    turn_limit=math.inf,
    threshold=0.0,
    stop_when_converged=False,
):
    outcome = _run(
        np.array([kind, value]),
        np.asarray(y0, dtype=float),
        gravity,
        rtol,
        time_limit,
        turn_limit,
        threshold,
        stop_when_converged,
    )
    return dict(zip(OUTCOME_FIELDS, outcome))


def test_a_constant_moment_turns_the_axis_by_m_t2_over_2i():
    """q = M t / I and phi = phi_0 - M t^2 / (2 I) (the pitch rate turns the axis angle down): a polynomial the
    fifth-order method integrates exactly."""
    moment, limit = 3.0, 0.8
    out = run(CONSTANT_MOMENT, moment, [0, -10, 0, 5, 0, 0], time_limit=limit)
    assert out["end"] == TIME_LIMIT and out["time"] == pytest.approx(limit, rel=1e-12)
    assert out["axis_turn"] == pytest.approx(-moment * limit**2 / (2 * INERTIA), rel=1e-12)
    turned = run(CONSTANT_MOMENT, moment, [0, -10, 0, 5, 0, 0], turn_limit=0.25)
    exact = math.sqrt(2 * INERTIA * 0.25 / moment)
    assert turned["end"] == TURNED and exact <= turned["time"] <= exact + MAX_STEP
    assert turned["axis_turn"] == pytest.approx(-moment * turned["time"] ** 2 / (2 * INERTIA), rel=1e-12)


def test_linear_drag_decays_the_speed_exponentially_and_stops_it():
    """m dv/dt = -c v: |v| = v0 exp(-c t / m); the run stops at the first step below the stop speed."""
    c, v0 = 4.0, 100.0
    out = run(LINEAR_DRAG, c, [0, -10, 0.3, 60.0, -80.0, 0], time_limit=10.0)
    assert out["end"] == STOPPED and out["final_speed"] < 1e-3
    assert out["final_speed"] == pytest.approx(v0 * math.exp(-c * out["time"] / MASS), rel=1e-6)
    exact = MASS / c * math.log(v0 / 1e-3)
    assert exact <= out["time"] <= exact + MAX_STEP
    assert out["axis_turn"] == 0.0


def test_a_pendulum_swings_with_its_exact_period():
    """I d^2 phi / dt^2 = -k sin(phi) released from 1 rad: the period is 4 sqrt(I/k) K(sin^2(1/2)) (K the complete
    elliptic integral); after half of it the axis is at -1 rad, after all of it back at +1 rad."""
    from scipy.special import ellipk

    k = 2.0
    period = 4.0 * math.sqrt(INERTIA / k) * ellipk(math.sin(0.5) ** 2)
    half = run(PENDULUM, k, [0, -10, 1.0, 1.0, 0, 0], time_limit=0.5 * period)
    full = run(PENDULUM, k, [0, -10, 1.0, 1.0, 0, 0], time_limit=period)
    assert half["end"] == full["end"] == TIME_LIMIT
    assert half["axis_turn"] == pytest.approx(-2.0, abs=1e-6)
    assert full["axis_turn"] == pytest.approx(0.0, abs=1e-6)


def test_leaving_the_target_ends_the_run():
    """A point thrown up from 1 m below the surface under gravity: it leaves at Z = 0, at t = (v - sqrt(v^2 -
    2 g))/g."""
    g, v = 9.81, 10.0
    out = run(CONSTANT_MOMENT, 0.0, [0, -1.0, 0, 0, v, 0], gravity=g, rtol=1e-10)
    exact = (v - math.sqrt(v * v - 2 * g)) / g
    assert out["end"] == EXITED and exact <= out["time"] <= exact + MAX_STEP


def test_convergence_is_where_the_attack_angle_falls_below_the_threshold():
    """No load, a steady pitch rate turning the axis onto the (downward) velocity: the attack angle falls linearly
    from its peak at the start and crosses the threshold at (alpha0 - threshold) / q, at the constant speed."""
    alpha0, q, threshold = 0.3, 2.0, 0.01
    out = run(CONSTANT_MOMENT, 0.0, [0, -10, alpha0, 0.0, -50.0, q], threshold=threshold, stop_when_converged=True)
    assert out["end"] == CONVERGED
    assert out["max_attack_angle"] == pytest.approx(alpha0)
    assert out["convergence_speed"] == pytest.approx(50.0, rel=1e-12)
    exact = (alpha0 - threshold) / q
    assert exact <= out["time"] <= exact + MAX_STEP
