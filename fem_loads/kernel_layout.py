"""The layout of the compiled DAFL kernel's data (:mod:`fem_loads.compiled`): which arrays, in which order,
built from a :class:`~fem_loads.dafl.DAFLLoads` through its public attributes.

Kept apart from the kernel so that building the data needs no numba, and the kernel's module holds only
compiled code.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from . import images
from .dafl import DAFLLoads
from .resistance import ResistanceLaw
from .target import LayeredTarget
from .user_law import MAX_PARAMETERS, UserLaw

__all__ = [
    "KERNEL_ARRAYS",
    "kernel_data",
    "supports",
    "CONSTANT_MAX_RADIUS",
    "CONSTANT_HALF_ENTRY",
    "CONSTANT_CONTACT_WIDTH",
    "CONSTANT_CONTACT_INCIDENCE",
    "CONSTANT_CONTACT_OFFSET",
    "CONSTANT_GUARD",
    "CONSTANT_SMOOTH_CONTACT",
    "CONSTANT_SMOOTH_ENTRY",
    "CONSTANT_SEPARATION",
    "CONSTANT_USER_LAW",
    "CONSTANT_NEEDS_DEPTH",
    "CONSTANT_FRICTION",
    "CONSTANT_FRICTION_CAP",
    "CONSTANT_SURFACE_DEPTH",
    "CONSTANT_SURFACE_FRACTION",
    "CONSTANT_PLAIN",
    "N_CONSTANTS",
    "DATA_NORMAL_ARM",
    "DATA_POINTS",
    "DATA_WEIGHTS",
    "DATA_INVERSE_ENTRY",
    "DATA_HALF_ENTRY_LENGTH",
    "DATA_IMAGE_SIGNS",
    "DATA_POINT_SIGNS",
    "DATA_CONSTANTS",
    "DATA_LAWS",
    "DATA_TABLES",
    "DATA_TABLE_ROWS",
    "DATA_INTERFACES",
    "DATA_USER_LAW_ADDRESS",
    "DATA_EXPOSURE_COLUMNS",
    "DATA_EXPOSURE_START",
    "DATA_EXPOSURE_ROWS",
    "DATA_EXPOSURE_CORNERS",
    "DATA_EXPOSURE_FINE",
]

#: the positions of the scalars in the data's "constants" array
(
    CONSTANT_MAX_RADIUS,
    CONSTANT_HALF_ENTRY,
    CONSTANT_CONTACT_WIDTH,
    CONSTANT_CONTACT_INCIDENCE,
    CONSTANT_CONTACT_OFFSET,
    CONSTANT_GUARD,
    CONSTANT_SMOOTH_CONTACT,
    CONSTANT_SMOOTH_ENTRY,
    CONSTANT_SEPARATION,
    CONSTANT_USER_LAW,
    CONSTANT_NEEDS_DEPTH,
    CONSTANT_FRICTION,
    CONSTANT_FRICTION_CAP,
    CONSTANT_SURFACE_DEPTH,
    CONSTANT_SURFACE_FRACTION,
    CONSTANT_PLAIN,
    N_CONSTANTS,
) = range(17)


#: the arrays of the kernel's data, in order (:func:`kernel_data`): a plain tuple of arrays, which numba's
#: dispatcher types in C (a named tuple, or a function object in it, costs 100-200 us per call from Python)
KERNEL_ARRAYS = (
    "normal_arm",  # (6, m): [n | r x n] of the fundamental part's (or every) point
    "points",  # (3, m), m
    "weights",  # (m,), m^2
    "inverse_entry",  # (m,): 1 / l (1/m), zero with sharp entry
    "half_entry_length",  # (m,): l / 2 (m)
    "image_signs",  # (k, 6)
    "point_signs",  # (k, 3)
    "constants",  # the scalars, indexed as above
    "laws",  # (layers, 8): each layer's built-in coefficients (c0, k, c1, c2, c, n) or user law's parameters
    "tables",  # (2, rows): the layers' strength tables one after the other, depth (m) and stress (Pa)
    "table_rows",  # (layers, 2), int: each layer's first row in tables and its count
    "interfaces",  # (layers - 1,): the layers' interfaces (m below the surface)
    "user_law",  # (1,), int: the address of a user law's cfunc (USER_LAW_SIGNATURE), 0 without one
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
    DATA_CONSTANTS,
    DATA_LAWS,
    DATA_TABLES,
    DATA_TABLE_ROWS,
    DATA_INTERFACES,
    DATA_USER_LAW_ADDRESS,
    DATA_EXPOSURE_COLUMNS,
    DATA_EXPOSURE_START,
    DATA_EXPOSURE_ROWS,
    DATA_EXPOSURE_CORNERS,
    DATA_EXPOSURE_FINE,
) = range(len(KERNEL_ARRAYS))


def supports(loads: DAFLLoads) -> bool:
    """Whether :func:`dafl_kernel` computes ``loads``: every law and effect, except layers of more than
    one user function (the kernel calls one)."""
    laws = loads.law.laws if isinstance(loads.law, LayeredTarget) else (loads.law,)
    users = {law.source for law in laws if isinstance(law, UserLaw)}
    return len(users) == 0 or (len(users) == 1 and all(isinstance(law, UserLaw) for law in laws))


def _law_rows(loads: DAFLLoads) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, Any]:
    """``(laws, tables, table_rows, interfaces, user law's cfunc or None)`` of :func:`kernel_data`."""
    layered = isinstance(loads.law, LayeredTarget)
    laws = loads.law.laws if isinstance(loads.law, LayeredTarget) else (loads.law,)
    rows = np.zeros((len(laws), MAX_PARAMETERS))
    table_rows = np.zeros((len(laws), 2), dtype=np.int64)
    tables: list[np.ndarray] = [np.zeros((2, 0))]
    user = None
    for i, law in enumerate(laws):
        if isinstance(law, UserLaw):
            rows[i] = law.parameter_values
            user = law.compiled()
        else:
            assert isinstance(law, ResistanceLaw)
            rows[i, :6] = law.coefficients
            depths, stresses = law.table
            table_rows[i] = (sum(t.shape[1] for t in tables), len(depths))
            tables.append(np.stack([depths, stresses]))
    interfaces = loads.law.interfaces if isinstance(loads.law, LayeredTarget) else np.zeros(0)
    assert layered or len(interfaces) == 0
    return rows, np.ascontiguousarray(np.concatenate(tables, axis=1)), table_rows, np.asarray(interfaces, float), user


def kernel_data(loads: DAFLLoads) -> tuple[np.ndarray, ...]:
    """The arrays and constants of :func:`dafl_kernel` for ``loads`` (see :func:`supports`), in the order of
    :data:`KERNEL_ARRAYS`."""
    if not supports(loads):
        raise ValueError("the compiled load calls one user function: layers of different user laws run on numpy")
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
    laws, tables, table_rows, interfaces, user = _law_rows(loads)
    constants = np.zeros(N_CONSTANTS)
    constants[CONSTANT_MAX_RADIUS] = loads.max_radius
    constants[CONSTANT_HALF_ENTRY] = 0.5 * float(arrays["entry_length"].max()) if len(loads) else 0.0
    constants[CONSTANT_CONTACT_WIDTH] = loads.contact_width
    constants[CONSTANT_CONTACT_INCIDENCE] = loads.contact_incidence
    constants[CONSTANT_CONTACT_OFFSET] = 0.5 if loads.contact == "centred" else 0.0
    constants[CONSTANT_GUARD] = loads.normal_velocity_guard
    constants[CONSTANT_SMOOTH_CONTACT] = float(loads.contact_width > 0.0 or loads.contact_incidence > 0.0)
    constants[CONSTANT_SMOOTH_ENTRY] = float(loads.entry_smoothing > 0.0)
    constants[CONSTANT_SEPARATION] = float(loads.separation)
    constants[CONSTANT_USER_LAW] = float(user is not None)
    constants[CONSTANT_NEEDS_DEPTH] = float(loads.depth_dependent)
    if loads.friction is not None:
        constants[CONSTANT_FRICTION] = loads.friction.coefficient
        constants[CONSTANT_FRICTION_CAP] = loads.friction.cap or 0.0
    constants[CONSTANT_PLAIN] = float(
        isinstance(loads.law, ResistanceLaw)
        and loads.law.power == 0.0
        and not loads.law.strength_table
        and loads.separation
        and constants[CONSTANT_SMOOTH_CONTACT] != 0.0
        and constants[CONSTANT_SMOOTH_ENTRY] != 0.0
    )
    if loads.free_surface is not None:
        constants[CONSTANT_SURFACE_DEPTH] = loads.free_surface.depth
        constants[CONSTANT_SURFACE_FRACTION] = loads.free_surface.surface_fraction

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
        constants,
        contiguous(laws),
        tables,
        table_rows,
        contiguous(interfaces),
        np.array([0 if user is None else user.address], dtype=np.int64),
        *_exposure_arrays(loads),
    )


def _exposure_arrays(loads: DAFLLoads) -> tuple[np.ndarray, ...]:
    """``exposure_columns``, ``exposure_start``, ``exposure_rows``, ``exposure_corners`` and ``exposure_fine`` of
    :func:`kernel_data` (empty without)."""
    exposure = loads.exposure
    if exposure is None:
        return (
            np.zeros(0, dtype=np.int64),
            np.zeros(1, dtype=np.int64),
            np.zeros(0, dtype=np.int64),
            np.zeros(0, dtype=np.int64),
            np.zeros(0, dtype=np.int64),
        )
    return tuple(
        np.ascontiguousarray(array, dtype=np.int64)
        for array in (
            exposure.columns,
            exposure.cell_start,
            exposure.cell_rows,
            exposure.cell_corners,
            exposure.cell_fine,
        )
    )
