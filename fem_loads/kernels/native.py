"""The compiled forms of the scalar definitions the numpy path shares, and the call into a user's law.

Each compiled form (:data:`point_stress`, :data:`face_frame`, ...) is numba's compilation of the one ``*_scalars``
definition the numpy path evaluates, for the compiled kernels to inline.  :func:`call_user_law` calls a user's law
through the address of its ``cfunc`` (:meth:`fem_loads.user_law.UserLaw.compiled`): the kernels take the address
as data, so they are compiled and cached once for every law.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import numpy as np
from llvmlite import ir
from numba import njit, types
from numba.extending import intrinsic, overload, register_jitable

from .. import factors
from ..exposure import cell_exposure_scalars, corner_exposure, cube_cell_scalars, fine_exposure
from ..factors import (
    add_term,
    entry_factor_scalars,
    friction_stress_scalars,
    in_contact_scalars,
    layer_share_scalars,
    point_stress_scalars,
    switches_scalars,
)
from ..resistance import normal_stress_scalars, polynomial_stress_scalars, power_term_scalars, table_stress_scalars
from ..target import face_frame_scalars, face_height_scalars, slip_factor_scalars, slip_scalars
from ..user_law import MAX_PARAMETERS

__all__ = [
    "call_user_law",
    "slip_factor",
    "slip",
    "in_contact",
    "builtin_stress",
    "polynomial_stress",
    "power_term",
    "entry_factor",
    "layer_share",
    "friction_stress",
    "point_stress",
    "switches",
    "face_frame",
    "cube_cell",
    "cell_exposure",
    "law_stress",
    "law_value",
    "law_values",
]


#: a built-in law's coefficients ``(c0, k, c1, c2, c, n)`` and a user law's parameters, as the loops read them
Coefficients = tuple[float, float, float, float, float, float]
Parameters = tuple[float, float, float, float, float, float, float, float]


@overload(np.clip, inline="always")
def _clip_float(a, a_min, a_max):  # type: ignore[no-untyped-def]  # numba matches the names, without annotations
    """``np.clip`` on a float, which numba compiles only for arrays."""
    float_clip = lambda a, a_min, a_max: np.minimum(np.maximum(a, a_min), a_max)  # noqa: E731
    return float_clip if isinstance(a, types.Float) else None


@overload(table_stress_scalars, inline="always")
def _table_stress_at_a_point(depth, table_depths, table_stresses):  # type: ignore[no-untyped-def]
    """:func:`~fem_loads.resistance.table_stress_scalars` at one depth as ``np.interp`` computes it, without the
    arrays numba's ``np.interp`` builds for a single value (an allocation per point)."""
    if not isinstance(depth, types.Float):
        return lambda depth, table_depths, table_stresses: np.interp(depth, table_depths, table_stresses)

    def at_a_point(depth, table_depths, table_stresses):  # type: ignore[no-untyped-def]
        last = table_depths.shape[0] - 1
        if depth <= table_depths[0]:
            return table_stresses[0]
        if depth >= table_depths[last]:
            return table_stresses[last]
        j = np.searchsorted(table_depths, depth, side="right") - 1  # table_depths[j] <= depth < table_depths[j + 1]
        slope = (table_stresses[j + 1] - table_stresses[j]) / (table_depths[j + 1] - table_depths[j])
        return slope * (depth - table_depths[j]) + table_stresses[j]

    return at_a_point


@overload(add_term, inline="always")
def _add_term_always(value, term):  # type: ignore[no-untyped-def]
    """:func:`~fem_loads.factors.add_term` compiled: a branch on the term would stay in a loop's SIMD lanes."""
    return lambda value, term: value + term


# every *_scalars function of fem_loads.factors (its factors and the smooth step it imports) as numba sees them
# inside the pipeline, so that a new factor needs no line here (the plain functions stay plain)
# (law_velocity_scalars is not inlined at numba's level: its conditional expression trips the same pedantic SSA
# check as polynomial_stress_scalars below; LLVM inlines it all the same)
for _name, _function in vars(factors).items():
    if _name.endswith("_scalars") and callable(_function):
        _inline = "never" if _function is factors.law_velocity_scalars else "always"
        register_jitable(inline=_inline, error_model="numpy")(_function)
point_stress = njit(inline="always", error_model="numpy")(point_stress_scalars)
switches = njit(inline="always", error_model="numpy")(switches_scalars)
entry_factor = njit(inline="always", error_model="numpy")(entry_factor_scalars)
layer_share = njit(inline="always", error_model="numpy")(layer_share_scalars)
friction_stress = njit(inline="always", error_model="numpy")(friction_stress_scalars)
slip_factor = njit(inline="always", error_model="numpy")(slip_factor_scalars)
slip = njit(inline="always", error_model="numpy")(slip_scalars)
in_contact = njit(inline="always", error_model="numpy")(in_contact_scalars)
# the centre's height as numba sees it inside the face's frame
register_jitable(error_model="numpy")(face_height_scalars)
face_frame = njit(inline="always", error_model="numpy")(face_frame_scalars)
polynomial_stress = njit(inline="always", error_model="numpy")(polynomial_stress_scalars)
# the polynomial part as numba sees it inside normal_stress_scalars (the plain function stays plain; not
# inlined at numba's level, whose renaming of its augmented assignments trips a pedantic SSA check)
register_jitable(error_model="numpy")(polynomial_stress_scalars)
# the power term as numba sees it inside normal_stress_scalars, and for the passes that add it to a plain law
register_jitable(error_model="numpy")(power_term_scalars)
power_term = njit(inline="always", error_model="numpy")(power_term_scalars)
builtin_stress = njit(inline="always", error_model="numpy")(normal_stress_scalars)
cube_cell = njit(inline="always", error_model="numpy")(cube_cell_scalars)
# the cell's exposure and the two forms it calls, as numba sees them inside it (the plain functions stay plain)
register_jitable(error_model="numpy")(corner_exposure)
register_jitable(error_model="numpy")(fine_exposure)
cell_exposure = njit(inline="always", error_model="numpy")(cell_exposure_scalars)


@intrinsic
def _call_user_law_intrinsic(
    typingctx: Any,
    address: Any,
    normal_velocity: Any,
    depth: Any,
    p0: Any,
    p1: Any,
    p2: Any,
    p3: Any,
    p4: Any,
    p5: Any,
    p6: Any,
    p7: Any,
) -> Any:
    """Call the cfunc at ``address`` (an int64) with ``(Vn, z, p0 .. p7)``: a C call through a pointer, so the
    kernel and the step are compiled once for every user law and take the law as data."""
    signature = types.float64(types.int64, *([types.float64] * (2 + MAX_PARAMETERS)))

    def codegen(context: Any, builder: Any, signature: Any, arguments: Any) -> Any:
        function_type = ir.FunctionType(ir.DoubleType(), [ir.DoubleType()] * (2 + MAX_PARAMETERS))
        pointer = builder.inttoptr(arguments[0], function_type.as_pointer())
        return builder.call(pointer, arguments[1:])

    return signature, codegen


#: the intrinsic as the kernels call it, (address, Vn, z, p0 .. p7) -> sigma (numba passes the typing context)
call_user_law: Callable[..., float] = _call_user_law_intrinsic


@njit(cache=True, inline="always", error_model="numpy")
def law_values(law: Any) -> tuple[Coefficients, Parameters]:
    """A :data:`~fem_loads.kernels.records.LAW` record's built-in coefficients ``(c0, k, c1, c2, c, n)`` and its user
    law's parameters, as tuples of floats: what a loop over the points reads once, not once per point."""
    u = law.user
    return (law.c0, law.k, law.c1, law.c2, law.c, law.n), (u[0], u[1], u[2], u[3], u[4], u[5], u[6], u[7])


@njit(cache=True, inline="always", error_model="numpy")
def law_value(
    coefficients: Coefficients,
    parameters: Parameters,
    address: int,
    normal_velocity: float,
    depth: float,
    depths: np.ndarray,
    stresses: np.ndarray,
) -> float:
    """The stress (Pa) of one law at ``Vn`` (m/s) and depth (m): the user's function at ``address`` with its
    ``parameters``, or (``address`` 0) the built-in law with its ``coefficients`` (:func:`law_values`) and the
    strength table ``depths``, ``stresses`` (empty: none)."""
    if address != 0:
        u = parameters
        return call_user_law(address, normal_velocity, depth, u[0], u[1], u[2], u[3], u[4], u[5], u[6], u[7])
    c0, k, c1, c2, c, n = coefficients
    return builtin_stress(normal_velocity, depth, c0, k, c1, c2, c, n, depths, stresses)


@njit(cache=True, inline="always", error_model="numpy")
def law_stress(
    law: Any, address: int, normal_velocity: float, depth: float, depths: np.ndarray, stresses: np.ndarray
) -> float:
    """:func:`law_value` of one layer's law, a :data:`~fem_loads.kernels.records.LAW` record."""
    coefficients, parameters = law_values(law)
    return law_value(coefficients, parameters, address, normal_velocity, depth, depths, stresses)
