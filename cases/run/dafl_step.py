"""The compiled Runge-Kutta step of the DAFL load (imported through :mod:`.compiled` only, which sets
numba's cache folder first).  The kernel is a global here, so numba can cache the step."""

from __future__ import annotations

import numpy as np
from numba import njit

from dynamics.compiled_rk import Body, Start, Tableau, rk_step
from fem_loads.kernels.mesh_loop import dafl_kernel

__all__ = ["dafl_step"]


@njit(cache=True, error_model="numpy")
def dafl_step(
    data: tuple[np.ndarray, ...],
    body: Body,
    method: Tableau,
    start: Start,
    h: float,
    given: np.ndarray,
    has_given: bool,
    out: np.ndarray,
) -> None:
    """:func:`dynamics.compiled_rk.rk_step` with the load :func:`fem_loads.kernels.mesh_loop.dafl_kernel`."""
    rk_step(dafl_kernel, data, body, method, start, h, given, has_given, out)
