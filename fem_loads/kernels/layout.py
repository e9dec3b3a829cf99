"""The layout of the compiled DAFL kernel's data (:mod:`fem_loads.kernels.mesh_loop`): which arrays, in which order,
built from a :class:`~fem_loads.dafl.DAFLLoads` through its public attributes (without numba)."""

from __future__ import annotations

import numpy as np

from .. import images
from ..dafl import DAFLLoads
from .records import pack_effects, pack_laws

__all__ = ["KERNEL_ARRAYS", "kernel_data"]  # and each array's index, DATA_*

# the index of each array in the kernel's data (:func:`kernel_data`), a plain tuple of arrays, which numba's
# dispatcher types in C (a named tuple, or a function object in it, costs more per call from Python)
DATA_NORMAL_ARM = 0  # (6, m): [n | r x n] of the fundamental part's (or every) point
DATA_POINTS = 1  # (3, m), m
DATA_WEIGHTS = 2  # (m,), m^2
DATA_INVERSE_ENTRY = 3  # (m,): 1 / l (1/m), zero with sharp entry
DATA_HALF_ENTRY_LENGTH = 4  # (m,): l / 2 (m)
DATA_IMAGE_SIGNS = 5  # (k, 6)
DATA_POINT_SIGNS = 6  # (k, 3)
DATA_EFFECTS = 7  # (1,) EFFECTS record: the ramps, friction, free surface, user law (records)
DATA_LAWS = 8  # (layers,) LAW records: each layer's coefficients or user parameters (records)
DATA_TABLES = 9  # (2, columns): the layers' strength tables one after the other, depth (m) and stress (Pa)
DATA_INTERFACES = 10  # (layers - 1,): the layers' interfaces (m below the surface)
DATA_EXPOSURE_COLUMNS = 11  # (c,), int: the points that can be hidden (Exposure.columns); empty for a convex body
DATA_EXPOSURE_START = 12  # (6 N^2 + 1,), int: where each cell's hidden rows start (Exposure.cell_start)
DATA_EXPOSURE_ROWS = 13  # (h,), int: the rows hidden at a corner of each cell, cell after cell (Exposure.cell_rows)
DATA_EXPOSURE_CORNERS = 14  # (h,), int: at which of its corners, a bit each (Exposure.cell_corners)
DATA_EXPOSURE_FINE = 15  # (h,), int: a refined cell's sub-nodes hidden, a bit each, or -1 (Exposure.cell_fine)
#: the arrays' names, in order
KERNEL_ARRAYS = tuple(name[5:].lower() for name in list(globals()) if name.startswith("DATA_"))


def kernel_data(loads: DAFLLoads) -> tuple[np.ndarray, ...]:
    """The arrays and records of :func:`dafl_kernel` for ``loads`` (its target
    :func:`~fem_loads.kernels.records.compilable`), in the order of :data:`KERNEL_ARRAYS`."""
    quadrature = loads.quadrature
    if quadrature.mirror_images is not None:
        index = quadrature.mirror_images[0]
        image_signs, point_signs = (
            images.image_signs(quadrature.mirror_signs),
            images.point_signs(quadrature.mirror_signs),
        )
    else:
        index = np.arange(len(loads))
        image_signs, point_signs = np.ones((1, 6)), np.ones((1, 3))
    arrays = loads.point_arrays()
    entry_length = arrays["entry_length"][index]
    laws, tables, interfaces, address = pack_laws(loads.law)

    def contiguous(array: np.ndarray) -> np.ndarray:
        return np.ascontiguousarray(array, dtype=float)

    return (
        contiguous(arrays["normal_arm"][:, index]),
        contiguous(arrays["points"][:, index]),
        contiguous(arrays["weights"][index]),
        contiguous(1.0 / entry_length if loads.entry_smoothing else np.zeros(len(index))),
        contiguous(0.5 * entry_length),
        contiguous(image_signs),
        contiguous(point_signs),
        pack_effects(loads, loads.effect_values(), address),
        laws,
        tables,
        contiguous(interfaces),
        *_exposure_arrays(loads),
    )


def _exposure_arrays(loads: DAFLLoads) -> tuple[np.ndarray, ...]:
    """``exposure_columns``, ``exposure_start``, ``exposure_rows``, ``exposure_corners`` and ``exposure_fine`` of
    :func:`kernel_data` (empty without)."""
    e = loads.exposure
    empty = (np.zeros(0), np.zeros(1), np.zeros(0), np.zeros(0), np.zeros(0))
    arrays = empty if e is None else (e.columns, e.cell_start, e.cell_rows, e.cell_corners, e.cell_fine)
    return tuple(np.ascontiguousarray(array, dtype=np.int64) for array in arrays)
