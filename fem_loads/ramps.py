"""Smooth switches: the quintic smooth step that turns the DAFL's on/off conditions (entry, contact, layer
interfaces) into continuous loads, ``S(t) = t^3 (10 - 15 t + 6 t^2)`` on [0, 1], 0 below and 1 above: two
continuous derivatives, so a Runge-Kutta step across a switch keeps its order, and slope at most ``S'(1/2) = 15/8``
(docs/model.md)."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["smooth_step_scalars", "add_term", "MAX_SLOPE"]

MAX_SLOPE = 15.0 / 8.0  # the largest dS/dt, at t = 1/2


def smooth_step_scalars(t: Any) -> Any:
    """``S(clip(t, 0, 1))`` on a float or an array: the one definition, which the numpy path evaluates on
    arrays and the compiled kernels (:mod:`fem_loads.compiled`, :mod:`fem_loads.revolved`) compile."""
    t = np.clip(t, 0.0, 1.0)  # on an array one pass where maximum then minimum take two
    # t^3 (10 + t (6 t - 15)); on an array the augmented operations work in place (no temporaries)
    step = 6.0 * t
    step -= 15.0
    step *= t
    step += 10.0
    step *= t
    step *= t
    step *= t
    return step


def add_term(value: Any, term: float) -> Any:
    """``value + term``: on an array in place, and skipped where ``term`` is 0 (an array pass fewer).  Compiled
    (:mod:`fem_loads.native`) it is always added, so that a loop over the points keeps no branch."""
    if term != 0.0:
        value += term
    return value
