"""The compiled step of a run (``numerics.kernel = "compiled"``), with numba's cache named for its code.

The compiled Runge-Kutta step (:mod:`dynamics.compiled`) is specialised on the load kernel it calls
(:mod:`fem_loads.compiled`), another package's module.  numba's documentation warns that its cache
does not notice changes of functions defined in other files than the cached one (numba 0.68 did
notice a changed load kernel here, but that is not promised).  So numba's cache lives in a folder
named for the digest of both sources and numba's version, ``$PENETRATE_CACHE_DIR/numba/<digest>``
(``$NUMBA_CACHE_DIR/<digest>`` when that is set),
set before either module is imported: changed code gets a folder of its own and compiles afresh.
"""

from __future__ import annotations

import hashlib
import importlib.util
import os
import sys
from pathlib import Path

import numpy as np

from .persistence import cache_dir

__all__ = ["compiled_step", "numba_cache_folder", "COMPILED_SOURCES"]

COMPILED_SOURCES = ("dynamics.compiled", "fem_loads.compiled")


def numba_cache_folder() -> Path:
    """``$PENETRATE_CACHE_DIR/numba/<digest of the compiled sources and numba's version>``."""
    import numba

    digest = hashlib.sha256(numba.__version__.encode())
    for name in COMPILED_SOURCES:
        digest.update(Path(importlib.util.find_spec(name).origin).read_bytes())
    root = os.environ.get("NUMBA_CACHE_DIR")
    return (Path(root) if root else cache_dir() / "numba") / digest.hexdigest()[:16]


def _import_compiled():
    if not all(name in sys.modules for name in COMPILED_SOURCES):
        from numba import config

        config.CACHE_DIR = str(numba_cache_folder())
    from dynamics import compiled as step
    from fem_loads import compiled as load

    return step, load


def compiled_step(loads, method, body, weight: np.ndarray | None):
    """The compiled load, Runge-Kutta step and exit height for a scene's loads (a ``DAFLLoads``).

    Returns ``(load, method, lowest_height)``: a :class:`~dynamics.compiled.CompiledLoad` (plus
    ``weight``, N, world frame, when given), the :class:`~dynamics.compiled.CompiledRungeKutta` of
    ``method``, and ``lowest_height(position, rotation)`` for the exit event.
    """
    step, load = _import_compiled()
    data = load.kernel_data(loads)
    return (step.CompiledLoad(load.dafl_kernel, data, weight), step.CompiledRungeKutta(method),
            lambda position, rotation: load.lowest_height_kernel(data, position, rotation))
