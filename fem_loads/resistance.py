"""Resistance functions: the normal stress of the target on a surface element, defined once.

Every built-in law is one function of the element's normal velocity ``Vn`` (m/s, positive into the target) and
its depth ``z`` (m below the target surface), :func:`normal_stress_scalars`:

    sigma_n = s(z) + c1 Vn + c2 Vn^2 + c Vn^n,    s(z) = c0 + k max(z, 0) + table(z)

The families a scene names are choices of these coefficients (docs/laws.md gives each one's source):

* cavity expansion, ``A sigma_0 + B rho_0 Vn^2``: ``c0 = A sigma_0``, ``c2 = B rho_0``;
* polynomial, ``c0 + c1 Vn + c2 Vn^2``;
* power, ``c0 + c Vn^n``;
* any of them with depth-dependent strength (``k``, or a table).

Like the factors (:mod:`fem_loads.factors`) it is written on floats and numpy arrays alike, for the numpy path
and the compiled kernel.  A law of a user's own (:mod:`fem_loads.user_law`) takes the same first two arguments.
For ``Vn < 0``, where only a load without separation evaluates it, the velocity terms are odd
(``c2 Vn |Vn|``, ``c sign(Vn) |Vn|^n``).
"""

from __future__ import annotations

import inspect
import math
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .factors import add_term

__all__ = [
    "ResistanceLaw",
    "COEFFICIENTS",
    "NAMED_LAWS",
    "LAW_FAMILIES",
    "resistance_law",
    "locking_cavity_expansion",
    "concrete_cavity_expansion",
    "concrete_strength_factor",
    "normal_stress_scalars",
    "polynomial_stress_scalars",
    "power_term_scalars",
    "UnknownLawError",
]

#: the built-in families a scene can name (``law = {model = ...}``), each with the coefficients it takes
LAW_FAMILIES = {
    "cavity_expansion": ("A", "sigma_0", "B", "rho_0"),
    "polynomial": ("c0", "c1", "c2"),
    "power": ("c0", "c", "n"),
}


class UnknownLawError(ValueError):
    """A law name that :data:`NAMED_LAWS` does not hold; the message lists the names it does."""


def polynomial_stress_scalars(normal_velocity: Any, depth: Any, c0: float, k: float, c1: float, c2: float) -> Any:
    """``c0 + k max(z, 0) + c1 Vn + c2 Vn |Vn|`` (Pa): :func:`normal_stress_scalars` without the power term and
    the table, and the whole law when it has neither (no calls: a compiled loop using it alone runs in SIMD lanes)."""
    # on arrays the augmented operations work in place (one temporary)
    stress = np.abs(normal_velocity)
    stress *= c2
    stress = add_term(stress, c1)
    stress *= normal_velocity
    stress += c0
    if k != 0.0:
        stress += k * np.maximum(depth, 0.0)
    return stress


def power_term_scalars(normal_velocity: Any, c: float, n: float) -> Any:
    """The power term ``c Vn |Vn|^(n - 1)`` (Pa) of :func:`normal_stress_scalars`: odd in ``Vn``, as the dynamic
    term ``c2 Vn |Vn|`` is."""
    return c * np.sign(normal_velocity) * np.abs(normal_velocity) ** n


def normal_stress_scalars(
    normal_velocity: Any,
    depth: Any,
    c0: float,
    k: float,
    c1: float,
    c2: float,
    c: float,
    n: float,
    table_depths: np.ndarray,
    table_stresses: np.ndarray,
) -> Any:
    """``sigma_n`` (Pa) of the built-in law at normal velocity ``Vn`` (m/s) and depth ``z`` (m below the surface).

    ``Vn`` and ``z`` are floats or arrays of one shape; the coefficients are those of :class:`ResistanceLaw`.
    ``table_depths`` (m, increasing) and ``table_stresses`` (Pa): the strength table, both empty without one.
    """
    stress = polynomial_stress_scalars(normal_velocity, depth, c0, k, c1, c2)
    if c != 0.0:
        stress += power_term_scalars(normal_velocity, c, n)
    if table_depths.shape[0] > 0:
        stress += table_stress_scalars(depth, table_depths, table_stresses)
    return stress


#: the built-in law's coefficients by name, in the order :func:`normal_stress_scalars` takes them: the one place
#: the order is written (:attr:`ResistanceLaw.coefficients` and the kernels' law record read it)
COEFFICIENTS = tuple(inspect.signature(normal_stress_scalars).parameters)[2:8]


def table_stress_scalars(depth: Any, table_depths: np.ndarray, table_stresses: np.ndarray) -> Any:
    """The strength table's stress (Pa) at ``depth`` (m; a float or an array): linear between its rows, the first
    and last rows' values beyond them (``np.interp``)."""
    return np.interp(depth, table_depths, table_stresses)


_NO_TABLE = np.zeros(0)


@dataclass(frozen=True)
class ResistanceLaw:
    """A built-in resistance law: the coefficients of :func:`normal_stress_scalars`.

    Parameters
    ----------
    c0 : float
        Pa (``A sigma_0`` of cavity expansion): the stress at vanishing normal velocity at the surface.
    c2 : float
        kg/m^3 (``B rho_0``): the coefficient of ``Vn^2``.
    name : str
        A label for reports.
    c1 : float
        Pa s/m: the coefficient of ``Vn``.
    c, n : float
        Pa (s/m)^n and ``0 < n <= 10``: the term ``c Vn^n``.
    k : float
        Pa/m: the strength's growth with depth below the surface.
    strength_table : tuple of (depth, stress) pairs, optional
        Extra strength (Pa) against depth (m, increasing), linear between rows and constant beyond.
    """

    c0: float
    c2: float
    name: str = "custom"
    c1: float = 0.0
    c: float = 0.0
    n: float = 1.0
    k: float = 0.0
    strength_table: tuple[tuple[float, float], ...] = ()
    #: the strength table's depths (m) and stresses (Pa) as arrays, both empty without one
    table: tuple[np.ndarray, np.ndarray] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        for field_name in ("c0", "c2", "c1", "c", "k"):
            value = getattr(self, field_name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{field_name} = {value}: must be a finite number >= 0")
        if not (math.isfinite(self.n) and 0.0 < self.n <= 10.0):
            raise ValueError(f"n = {self.n}: must lie in (0, 10]")
        table = np.array(self.strength_table, dtype=float).reshape(-1, 2)
        if not (np.all(np.isfinite(table)) and np.all(table[:, 1] >= 0.0) and np.all(np.diff(table[:, 0]) > 0.0)):
            raise ValueError("strength_table: (depth, stress) rows with increasing depths and stresses >= 0")
        depths, stresses = (np.ascontiguousarray(table[:, 0]), np.ascontiguousarray(table[:, 1]))
        object.__setattr__(self, "table", (depths, stresses) if len(table) else (_NO_TABLE, _NO_TABLE))

    @classmethod
    def from_coefficients(cls, A: float, sigma_0: float, B: float, rho_0: float, name: str = "custom") -> ResistanceLaw:
        """The law from its dimensionless coefficients and the target's ``sigma_0`` (Pa), ``rho_0`` (kg/m^3)."""
        return cls(A * sigma_0, B * rho_0, name)

    @property
    def depth_dependent(self) -> bool:
        """Whether the stress depends on depth (``k > 0`` or a table)."""
        return self.k != 0.0 or len(self.strength_table) > 0

    @property
    def coefficients(self) -> tuple[float, float, float, float, float, float]:
        """:data:`COEFFICIENTS`' values, in the order :func:`normal_stress_scalars` takes them."""
        c0, k, c1, c2, c, n = (float(getattr(self, name)) for name in COEFFICIENTS)
        return c0, k, c1, c2, c, n

    def normal_stress(self, normal_velocity: np.ndarray, depth: np.ndarray | float = 0.0) -> np.ndarray:
        """``sigma_n`` (Pa) at ``Vn`` (m/s) and depth (m below the surface); the caller applies separation."""
        return np.asarray(
            normal_stress_scalars(np.asarray(normal_velocity, dtype=float), depth, *self.coefficients, *self.table)
        )


def locking_cavity_expansion(
    sigma_0: float, rho_0: float, locking_strain: float, name: str = "locking cavity expansion"
) -> ResistanceLaw:
    """Spherical cavity expansion in an elastic-plastic-locking soil, rigid-locking limit: ``A sigma_0 + B rho_0 V^2``
    for a soil of strength ``sigma_0`` (Pa) and density ``rho_0`` (kg/m^3) that locks at the volumetric strain
    ``eta*`` (``locking_strain``), with ``A = (2/3)(1 - ln eta*)`` and
    ``B = [3/2 - 2 eta*^(1/3) + eta*^(4/3)/2] / (1 - eta*) + eta*^(1/3)``; docs/evidence-laws.md derives them and
    compares them with the paper's dynamic cavity-expansion laws."""
    if not (0.0 < locking_strain < 1.0):
        raise ValueError(f"locking_strain = {locking_strain}: must lie in (0, 1)")
    eta = locking_strain
    cube = eta ** (1.0 / 3.0)
    a = 2.0 / 3.0 * (1.0 - math.log(eta))
    b = (1.5 - 2.0 * cube + 0.5 * eta * cube) / (1.0 - eta) + cube
    return ResistanceLaw.from_coefficients(a, sigma_0, b, rho_0, name)


def concrete_strength_factor(compressive_strength: float) -> float:
    """``S = 82.6 (f'c / 1 MPa)^-0.544``: the static coefficient of concrete from its unconfined compressive
    strength ``f'c`` (Pa), Frew, Hanchak, Green and Forrestal's empirical fit to penetration tests (IJIE 1998)."""
    if not (math.isfinite(compressive_strength) and compressive_strength > 0.0):
        raise ValueError(f"compressive_strength = {compressive_strength}: must be a finite number > 0")
    return 82.6 * (compressive_strength / 1e6) ** -0.544


def concrete_cavity_expansion(
    compressive_strength: float, density: float, strength_factor: float | None = None, name: str = "concrete"
) -> ResistanceLaw:
    """Forrestal's spherical cavity expansion for concrete, ``sigma_n = S f'c + rho Vn^2``, from the unconfined
    compressive strength ``f'c`` (Pa) and the density ``rho`` (kg/m^3); ``S`` (``strength_factor``) defaults to
    :func:`concrete_strength_factor`."""
    factor = concrete_strength_factor(compressive_strength) if strength_factor is None else strength_factor
    return ResistanceLaw.from_coefficients(factor, compressive_strength, 1.0, density, name)


NAMED_LAWS: dict[str, ResistanceLaw] = {
    # brief section 2: Forrestal and Luk's soil, the paper's default
    "soil": ResistanceLaw.from_coefficients(1.718, 10e6, 1.227, 1860.0, "soil"),
    # spherical dynamic cavity expansion in an elastic-plastic-locking soil
    "soil_dynamic_cavity_expansion": ResistanceLaw(20.268e6, 2239.1, "soil_dynamic_cavity_expansion"),
    "softer_soil": ResistanceLaw(13.521e6, 1925.6, "softer_soil"),
}


def resistance_law(name: str) -> ResistanceLaw:
    """A named law of :data:`NAMED_LAWS`."""
    try:
        return NAMED_LAWS[name]
    except KeyError:
        raise UnknownLawError(f"law = {name!r}: must be one of {sorted(NAMED_LAWS)}") from None
