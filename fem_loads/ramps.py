"""Smooth switches: the step that turns the DAFL's on/off conditions into continuous loads.

The sharp DAFL switches a point's stress on when the point enters the target and when its normal
velocity becomes positive, and a layered target switches its law at each interface: each is a jump
of the load, which an explicit integrator crosses at first order and which makes the load chatter
where the state sits on the switch (the shank at ``Vn = 0`` once the attack angle has decayed).
Here each switch is the quintic smooth step

    S(t) = t^3 (10 - 15 t + 6 t^2)  on [0, 1],   0 below,   1 above,

applied to a scaled distance from the switch: continuous with two continuous derivatives (so a
Runge-Kutta method crossing it keeps its order: the error of a step across it is O(h^4) for RK4)
and Lipschitz, with slope at most ``S'(1/2) = 15/8`` per unit of ``t``.  As the width of a
switch goes to zero the load converges to the sharp one.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["smooth_step_scalars", "MAX_SLOPE"]

MAX_SLOPE = 15.0 / 8.0  # the largest dS/dt, at t = 1/2


def smooth_step_scalars(t: Any) -> Any:
    """``S(clip(t, 0, 1))`` on a float or an array: the one definition, which the numpy path evaluates on
    arrays and the compiled kernels (:mod:`fem_loads.compiled`, :mod:`fem_loads.revolved`) compile."""
    t = np.minimum(np.maximum(t, 0.0), 1.0)
    # t^3 (10 + t (6 t - 15)); on an array the augmented operations work in place (no temporaries)
    step = 6.0 * t
    step -= 15.0
    step *= t
    step += 10.0
    step *= t
    step *= t
    step *= t
    return step
