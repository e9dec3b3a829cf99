"""The compiled Runge-Kutta step (dynamics/compiled_rk.py) against exact solutions and the Python step."""

from __future__ import annotations

import math

import numpy as np
import pytest
from numba import njit
from scipy.spatial.transform import Rotation

from cases.run.compiled import _import_compiled
from dynamics import RK4, DormandPrince54, ErrorControl, FixedStep, RigidBody, SpeedBelow, State, simulate
from dynamics.quaternion import from_rotation_matrix, rotation_matrix

step, _ = _import_compiled()  # numba's cache in the folder named for the compiled code

I_AXIAL, I_TRANSVERSE = 0.25, 2.3
BODY = RigidBody(75.0, np.diag([I_AXIAL, I_TRANSVERSE, I_TRANSVERSE]))


@njit(cache=True)
def _spring_and_vane(data, position, velocity, rotation, angular_velocity, out):
    """F = -k x - d v (world); M = -c omega + s (e_x x R^T e_Z) (body): a damped spring and a weathervane."""
    k, d, c, s = data[0][0], data[0][1], data[0][2], data[0][3]
    for i in range(3):
        out[i] = -k * position[i] - d * velocity[i]
        out[3 + i] = -c * angular_velocity[i]
    up1, up2 = rotation[2, 1], rotation[2, 2]  # R^T e_Z
    out[4] += s * (-up2)  # e_x x up = (0, -up_z, up_y)
    out[5] += s * up1


@njit(cache=True, error_model="numpy")
def _spring_and_vane_step(data, body, method, start, h, given, has_given, out):
    step.rk_step(_spring_and_vane, data, body, method, start, h, given, has_given, out)


def _load(k=4.0e5, d=0.0, c=0.0, s=0.0):
    return step.CompiledLoad(_spring_and_vane, (np.array([k, d, c, s]),), _spring_and_vane_step)


def _start() -> State:
    r0 = Rotation.from_rotvec([0.3, -0.5, 0.2]).as_matrix()
    return State(
        0.0,
        np.array([0.1, -0.2, 0.05]),
        np.array([1.0, 2.0, 3.0]),
        from_rotation_matrix(r0),
        np.array([40.0, 3.0, -2.0]),
    )


def test_compiled_rk4_converges_at_fourth_order_to_the_harmonic_oscillator():
    """x'' = -(k/m) x: the exact cosine, and the error falls 16-fold per halving."""
    load, start = _load(), _start()
    omega = math.sqrt(4.0e5 / BODY.mass)
    t = 0.05
    exact = start.position * math.cos(omega * t) + start.velocity / omega * math.sin(omega * t)
    errors = []
    for h in (1e-3, 5e-4, 2.5e-4):
        trajectory = simulate(BODY, load, start, step.CompiledRungeKutta(RK4()), FixedStep(h), time_limit=t)
        errors.append(np.abs(trajectory.position[-1] - exact).max())
    rates = np.log2(np.array(errors[:-1]) / np.array(errors[1:]))
    assert np.all((rates > 3.7) & (rates < 4.3)), rates


def test_compiled_attitude_is_the_torque_free_top():
    """No moment: the exact precession of an axisymmetric top, |q| = 1 at every step."""
    load, start = _load(k=0.0), _start()
    trajectory = simulate(BODY, load, start, step.CompiledRungeKutta(RK4()), FixedStep(5e-4), time_limit=0.5)
    r0, w = rotation_matrix(start.attitude), start.angular_velocity
    lam = w[0] * (1 - I_AXIAL / I_TRANSVERSE)
    exact = (
        Rotation.from_rotvec(0.5 * (r0 @ (BODY.inertia @ w)) / I_TRANSVERSE).as_matrix()
        @ r0
        @ Rotation.from_rotvec([0.5 * lam, 0, 0]).as_matrix()
    )
    assert np.abs(rotation_matrix(trajectory.attitude[-1]) - exact).max() < 1e-8
    assert np.abs(np.linalg.norm(trajectory.attitude, axis=1) - 1.0).max() < 1e-14


@pytest.mark.parametrize(
    ("method", "control", "tolerance"),
    [
        (RK4, lambda: FixedStep(2e-4), 1e-12),
        # the error estimate is a small difference of the stages, its round-off moves each step's size by ~1e-12
        # relative, and the states follow their shifted times: 1e-9 of each quantity's scale
        (DormandPrince54, lambda: ErrorControl(1e-8), 1e-9),
    ],
    ids=["rk4", "dopri54"],
)
def test_compiled_step_equals_the_python_step(method, control, tolerance):
    """The same load (the kernel, called from Python by the Python step): the same trajectory to round-off,
    the same steps and stop event (the stop's search may take a few more or fewer partial steps: its
    iterations follow round-off)."""
    load, start = _load(d=800.0, c=3.0, s=50.0), _start()
    events = [SpeedBelow("stopped", 0.5)]
    python = simulate(BODY, load, start, method(), control(), time_limit=0.4, events=events)
    compiled = simulate(BODY, load, start, step.CompiledRungeKutta(method()), control(), time_limit=0.4, events=events)
    assert python.end_reason == compiled.end_reason == "stopped"
    a, b = dict(python.statistics), dict(compiled.statistics)
    evaluations = a.pop("load_evaluations"), b.pop("load_evaluations")
    # the compiled RK4 step also evaluates its end state (the Python driver does so after each step), so its
    # event search's partial steps cost one evaluation more each
    assert a == b and abs(evaluations[0] - evaluations[1]) <= 0.02 * evaluations[0]
    for name in ("position", "velocity", "attitude", "angular_velocity", "path_length", "force", "moment"):
        a, b = getattr(python, name), getattr(compiled, name)
        np.testing.assert_allclose(b, a, rtol=0, atol=tolerance * max(np.abs(a).max(), 1.0), err_msg=name)


def test_a_state_that_leaves_the_floats_ends_the_run():
    """An infinite spring stiffness: the step comes back non-finite and the run ends with its history."""
    load = _load(k=1e308)
    trajectory = simulate(BODY, load, _start(), step.CompiledRungeKutta(RK4()), FixedStep(1e-3), time_limit=1.0)
    assert trajectory.end_reason == "non_finite" and len(trajectory.time) >= 1
