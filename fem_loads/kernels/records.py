"""The law and its effects as the compiled kernels take them: typed records, packed in one place.

:data:`LAW` (one record per layer: the coefficients of :func:`~fem_loads.resistance.normal_stress_scalars`, a user
law's parameters, where its strength table lies) and :data:`EFFECTS` (the ramps, friction, free surface, front face
and what the mesh kernel derives from them once) are numpy structured arrays that numba reads by field name.
:func:`pack_laws` and :func:`pack_effects` build them, for the mesh kernel and the rings alike (the numpy load reads
the effects record too); :func:`compilable` is the one rule of which targets the compiled kernels take, and
:func:`in_lanes` of which loads they compute in SIMD lanes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ..resistance import COEFFICIENTS, ResistanceLaw
from ..target import LayeredTarget
from ..user_law import MAX_PARAMETERS, UserLaw

__all__ = ["LAW", "EFFECTS", "pack_laws", "pack_effects", "compilable", "in_lanes"]


#: one layer's law (SI units)
LAW = np.dtype(
    [
        ("c0", "f8"),  # Pa: the strength at the surface
        ("k", "f8"),  # Pa/m: its growth with depth
        ("c1", "f8"),  # Pa s/m: the coefficient of Vn
        ("c2", "f8"),  # kg/m^3: of Vn |Vn|
        ("c", "f8"),  # Pa (s/m)^n: of sign(Vn) |Vn|^n
        ("n", "f8"),
        ("user", "f8", (MAX_PARAMETERS,)),  # a user law's parameters, in its order
        ("table_first", "i8"),  # the strength table's first column in the tables' array
        ("table_count", "i8"),  # and its count (0: none)
    ]
)

#: the load's effects (SI units; flags as booleans)
EFFECTS = np.dtype(
    [
        ("contact_width", "f8"),  # w (m/s): the fixed part of the contact width W = w + delta U
        ("contact_incidence", "f8"),  # delta: the part of W proportional to the speed scale U
        ("contact_offset", "f8"),  # 0 one-sided, 1/2 centred
        ("smooth_contact", "b1"),  # W > 0 (else the sharp switch at Vn > guard U)
        ("guard", "f8"),  # the sharp switch's relative guard
        ("separation", "b1"),  # no stress below the contact ramp (else contact everywhere)
        ("smooth_entry", "b1"),  # points enter over their own extent (else sharply)
        ("entry_length", "f8"),  # m: the rings' entry length (the mesh's is per point)
        ("friction", "f8"),  # mu (0: none)
        ("friction_cap", "f8"),  # tau_s (Pa; 0: none)
        ("surface_depth", "f8"),  # D (m) of the free-surface reduction (0: none)
        ("surface_fraction", "f8"),  # f0 of the free-surface reduction
        ("surface_front", "b1"),  # it applies near the front face
        ("surface_rear", "f8"),  # m: and near a rear face at this depth (inf: not)
        ("user_law", "i8"),  # the address of a user law's cfunc (0: the built-in law)
        ("max_radius", "f8"),  # m: the farthest point from the centre of mass
        ("reach", "f8"),  # m: max_radius widened by half the longest entry length (DAFLLoads.reach)
        ("needs_depth", "b1"),  # the stress depends on each point's depth (beyond entering)
        ("plain", "b1"),  # in_lanes: built-in laws (tables, power terms), smooth ramps, separation: SIMD loops
        ("face_normal", "f8", (3,)),  # n: the front face n . X = d (world frame; target.FrontFace)
        ("face_offset", "f8"),  # d (m)
    ]
)


def _laws(law: ResistanceLaw | UserLaw | LayeredTarget) -> tuple[ResistanceLaw | UserLaw, ...]:
    return law.laws if isinstance(law, LayeredTarget) else (law,)


def in_lanes(
    law: ResistanceLaw | UserLaw | LayeredTarget, separation: bool, smooth_contact: bool, smooth_entry: bool
) -> bool:
    """Whether the compiled kernel computes this load in SIMD lanes (its plain loops, the effects record's
    ``plain``): built-in laws, one or each layer's, depth terms, strength tables and power terms included (the last
    two in passes of their own), with separation and both smooth ramps, the contact's and the entry's.  It computes
    any other load point by point, no faster than the numpy path (docs/performance.md)."""
    built_in = all(isinstance(each, ResistanceLaw) for each in _laws(law))
    return built_in and separation and smooth_contact and smooth_entry


def compilable(law: ResistanceLaw | UserLaw | LayeredTarget) -> bool:
    """Whether the compiled kernels take this target's law: every law, except layers of more than one user function
    or of user and built-in laws together (a kernel calls one function through one address)."""
    laws = _laws(law)
    users = {each.source for each in laws if isinstance(each, UserLaw)}
    return not users or (len(users) == 1 and all(isinstance(each, UserLaw) for each in laws))


def pack_laws(law: ResistanceLaw | UserLaw | LayeredTarget) -> tuple[np.ndarray, np.ndarray, np.ndarray, int]:
    """``(laws, tables, interfaces, address)``: one :data:`LAW` record per layer; their strength tables one after
    the other, shape (2, columns), depth (m) and stress (Pa); the interfaces (m below the surface, one fewer than
    the layers); and the user law's cfunc address (0: none).  Refuses what :func:`compilable` refuses."""
    if not compilable(law):
        raise ValueError("the compiled load calls one user function: layers of different user laws run on numpy")
    laws = _laws(law)
    records = np.zeros(len(laws), dtype=LAW)
    tables: list[np.ndarray] = [np.zeros((2, 0))]
    address = 0
    for record, each in zip(records, laws):
        if isinstance(each, UserLaw):
            record["user"] = each.parameter_values
            address = each.compiled().address
        else:
            assert isinstance(each, ResistanceLaw)
            for name, value in zip(COEFFICIENTS, each.coefficients):
                record[name] = value
            depths, stresses = each.table
            record["table_first"], record["table_count"] = sum(t.shape[1] for t in tables), len(depths)
            tables.append(np.stack([depths, stresses]))
    interfaces = law.interfaces if isinstance(law, LayeredTarget) else np.zeros(0)
    return records, np.ascontiguousarray(np.concatenate(tables, axis=1)), np.asarray(interfaces, float), address


def pack_effects(loads: Any, values: dict[str, Any], address: int = 0) -> np.ndarray:
    """One :data:`EFFECTS` record (shape (1,)) of the effects ``values`` of ``loads`` (a
    :class:`~fem_loads.dafl.DAFLLoads`; ``values`` from its :meth:`~fem_loads.dafl.DAFLLoads.effect_values` or
    :func:`~fem_loads.dafl.effect_values`) with the kernels' own fields, for the mesh kernel
    (:func:`~fem_loads.kernels.layout.kernel_data`) and the rings (:func:`~fem_loads.kernels.rings.ring_data`).
    ``address``: the user law's (:func:`pack_laws`; 0: none)."""
    values = dict(values)
    values["user_law"] = address
    values["plain"] = in_lanes(loads.law, loads.separation, values["smooth_contact"], values["smooth_entry"])
    assert set(values) == set(EFFECTS.names or ()), set(values) ^ set(EFFECTS.names or ())  # no field left at zero
    effects = np.zeros(1, dtype=EFFECTS)
    for name, value in values.items():
        effects[name] = value
    return effects
