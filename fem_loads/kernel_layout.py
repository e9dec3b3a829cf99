"""The layout of the compiled DAFL kernel's data (:mod:`fem_loads.compiled`): which arrays, in which order,
built from a :class:`~fem_loads.dafl.DAFLLoads` through its public attributes (without numba)."""

from __future__ import annotations

from typing import Any

import numpy as np

from . import images
from .dafl import DAFLLoads
from .law_record import compilable, pack

__all__ = ["KERNEL_ARRAYS", "kernel_data", "supports", "law_and_effects"]  # and each array's index, DATA_*

#: the arrays of the kernel's data, in order (:func:`kernel_data`): a plain tuple of arrays, which numba's
#: dispatcher types in C (a named tuple, or a function object in it, costs more per call from Python)
KERNEL_ARRAYS = (
    "normal_arm",  # (6, m): [n | r x n] of the fundamental part's (or every) point
    "points",  # (3, m), m
    "weights",  # (m,), m^2
    "inverse_entry",  # (m,): 1 / l (1/m), zero with sharp entry
    "half_entry_length",  # (m,): l / 2 (m)
    "image_signs",  # (k, 6)
    "point_signs",  # (k, 3)
    "effects",  # (1,) EFFECTS record: the ramps, friction, free surface, user law (law_record)
    "laws",  # (layers,) LAW records: each layer's coefficients or user parameters (law_record)
    "tables",  # (2, columns): the layers' strength tables one after the other, depth (m) and stress (Pa)
    "interfaces",  # (layers - 1,): the layers' interfaces (m below the surface)
    "exposure_columns",  # (c,), int: the points that can be hidden (Exposure.columns); empty for a convex body
    "exposure_start",  # (6 N^2 + 1,), int: where each cell's hidden rows start (Exposure.cell_start)
    "exposure_rows",  # (h,), int: the rows hidden at a corner of each cell, cell after cell (Exposure.cell_rows)
    "exposure_corners",  # (h,), int: at which of its corners, a bit each (Exposure.cell_corners)
    "exposure_fine",  # (h,), int: a refined cell's sub-nodes hidden, a bit each, or -1 (Exposure.cell_fine)
)
(
    DATA_NORMAL_ARM,
    DATA_POINTS,
    DATA_WEIGHTS,
    DATA_INVERSE_ENTRY,
    DATA_HALF_ENTRY_LENGTH,
    DATA_IMAGE_SIGNS,
    DATA_POINT_SIGNS,
    DATA_EFFECTS,
    DATA_LAWS,
    DATA_TABLES,
    DATA_INTERFACES,
    DATA_EXPOSURE_COLUMNS,
    DATA_EXPOSURE_START,
    DATA_EXPOSURE_ROWS,
    DATA_EXPOSURE_CORNERS,
    DATA_EXPOSURE_FINE,
) = range(len(KERNEL_ARRAYS))


def supports(loads: DAFLLoads) -> bool:
    """Whether :func:`dafl_kernel` computes ``loads``: :func:`~fem_loads.law_record.compilable` of its target."""
    return compilable(loads.law)


def law_and_effects(loads: DAFLLoads, **given: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """``(laws, tables, interfaces, effects)`` of ``loads``: its target and effects packed by
    :func:`~fem_loads.law_record.pack`, the arguments ``given`` (the rings': their ``entry_length`` and
    ``max_radius``) replacing the load's own."""
    entry_length = loads.point_arrays()["entry_length"]
    effects: dict[str, Any] = {
        "contact_width": loads.contact_width,
        "contact_incidence": loads.contact_incidence,
        "contact": loads.contact,
        "guard": loads.normal_velocity_guard,
        "separation": loads.separation,
        "entry_length": float(entry_length.max()) if len(entry_length) else 0.0,
        "friction": loads.friction,
        "free_surface": loads.free_surface,
        "max_radius": loads.max_radius,
        "front_face": loads.front_face,
    }
    return pack(loads.law, **(effects | given))


def kernel_data(loads: DAFLLoads) -> tuple[np.ndarray, ...]:
    """The arrays and records of :func:`dafl_kernel` for ``loads`` (see :func:`supports`), in the order of
    :data:`KERNEL_ARRAYS`."""
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
    laws, tables, interfaces, effects = law_and_effects(loads)

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
        effects,
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
