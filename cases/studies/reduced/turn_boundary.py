"""Characteristic speeds from the loads alone, without integrating a trajectory.

The paper conjectures that the characteristic convergent velocity follows
from the loads alone.  Two load-only estimates are computed here for a fully
embedded projectile (every surface point inside the target), both from the
pitch moment ``M_y`` about the centre of mass in the plane of the attack
angle ``alpha``:

* **Non-rotating crossing** ``V0(alpha)``: the speed at which the
  resistance centre crosses the centre of mass (``M_y = 0``) for a body
  translating at attack angle ``alpha`` with no angular velocity.  It grows
  without bound as ``alpha`` vanishes, so alone it predicts nothing.
* **Steady-turn boundary** ``V_turn(alpha)``: the same crossing in the state
  in which an unstable projectile actually moves, a steady turn: the axis
  rotates with the velocity at the pitch rate ``q = -F_perp / (m V)``
  (``F_perp``: the force normal to the velocity), solved together with the
  loads, which depend on ``q``.  Above ``V_turn`` a steady turn at that attack
  angle can hold (the moment keeps the angle); below, the moment restores.
  ``V_turn`` has a minimum over ``alpha``: below that speed no steady turn is
  possible at any attack angle, so the attack angle must collapse.  That
  minimum, ``fold_speed``, is the load-only prediction of the convergent
  velocity; the attack angle then needs a time set by the pitch inertia to
  collapse, so the trajectory converges somewhat below it (docs/paper.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np
from scipy import optimize

from dynamics.rigid_body import LoadFunction

__all__ = ["TurnBoundary", "pitch_moment", "turn_boundary"]

DEEP = np.array([0.0, 0.0, -1000.0])  # every surface point far inside the target
SPEEDS = np.arange(100.0, 3001.0, 25.0)  # m/s: the grid on which sign changes are sought
MAX_PITCH_RATE = 1e4  # rad/s: a steady-turn iteration beyond this has no fixed point


def pitch_moment(loads: LoadFunction, mass: float, speed: float, attack: float, steady_turn: bool) -> float:
    """``M_y`` (N m) at ``speed`` (m/s) and ``attack`` (rad), without or with the steady-turn pitch rate.

    NaN when the steady-turn pitch rate has no fixed point.
    """
    velocity = speed * np.array([math.cos(attack), 0.0, math.sin(attack)])
    normal = np.array([-math.sin(attack), 0.0, math.cos(attack)])
    q = 0.0
    for _ in range(60 if steady_turn else 0):
        force, _ = loads(DEEP, velocity, np.eye(3), np.array([0.0, q, 0.0]))
        q_next = -float(force @ normal) / (mass * speed)
        if not abs(q_next) < MAX_PITCH_RATE:
            return math.nan  # no steady turn: the fixed point runs away
        if abs(q_next - q) <= 1e-12 * max(1.0, abs(q)):
            q = q_next
            break
        q = q_next
    _, moment = loads(DEEP, velocity, np.eye(3), np.array([0.0, q, 0.0]))
    return float(moment[1])


def _crossing(loads: LoadFunction, mass: float, attack: float, steady_turn: bool, speeds: np.ndarray) -> float | None:
    """The highest speed where ``M_y`` changes sign between neighbours of the grid ``speeds`` (both finite),
    refined by Brent's method.  The grid is walked down from its top, so the speeds below the crossing cost
    nothing."""
    above = pitch_moment(loads, mass, speeds[-1], attack, steady_turn)
    for i in range(len(speeds) - 2, -1, -1):
        value = pitch_moment(loads, mass, speeds[i], attack, steady_turn)
        if math.isfinite(value) and math.isfinite(above) and np.sign(value) != np.sign(above):
            return optimize.brentq(
                lambda v: pitch_moment(loads, mass, v, attack, steady_turn), speeds[i], speeds[i + 1], xtol=0.01
            )
        above = value
    return None


@dataclass
class TurnBoundary:
    """Load-only speeds of one projectile (attack angles in degrees, speeds in m/s)."""

    attack_angles: list[float]
    non_rotating: list[float | None]
    steady_turn: list[float | None]
    fold_speed: float | None
    fold_attack_angle: float | None


def turn_boundary(
    loads: LoadFunction,
    mass: float,
    attack_angles: Sequence[float] = tuple(range(1, 21)),
    speeds: Sequence[float] | np.ndarray | None = None,
) -> TurnBoundary:
    """``V0(alpha)``, ``V_turn(alpha)`` and the minimum of ``V_turn`` over ``alpha``."""
    speeds = SPEEDS if speeds is None else np.asarray(speeds, dtype=float)
    non_rotating = [_crossing(loads, mass, math.radians(a), False, speeds) for a in attack_angles]
    turning = [_crossing(loads, mass, math.radians(a), True, speeds) for a in attack_angles]
    known = [(v, a) for v, a in zip(turning, attack_angles) if v is not None]
    if not known:
        return TurnBoundary(list(attack_angles), non_rotating, turning, None, None)
    v_min, a_min = min(known)
    # refine the minimum between the neighbouring angles of the grid
    k = list(attack_angles).index(a_min)
    lo = attack_angles[max(k - 1, 0)]
    hi = attack_angles[min(k + 1, len(attack_angles) - 1)]
    if hi > lo:

        def boundary(a: float) -> float:
            v = _crossing(loads, mass, math.radians(a), True, speeds)
            return v if v is not None else math.inf

        best = optimize.minimize_scalar(boundary, bounds=(lo, hi), method="bounded", options={"xatol": 0.05})
        if best.fun < v_min:
            v_min, a_min = float(best.fun), float(best.x)
    return TurnBoundary(list(attack_angles), non_rotating, turning, v_min, a_min)
