"""Cavity-expansion resistance laws ``sigma_n = A sigma_0 + B rho_0 Vn^2``."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = [
    "ResistanceLaw",
    "NAMED_LAWS",
    "resistance_law",
    "register_law",
    "locking_cavity_expansion",
    "UnknownLawError",
]


class UnknownLawError(ValueError):
    """A law name that :data:`NAMED_LAWS` does not hold; the message lists the names it does."""


@dataclass(frozen=True)
class ResistanceLaw:
    """Normal stress of the target on a surface element moving into it.

    Parameters
    ----------
    static_stress : float
        ``A sigma_0`` (Pa): the stress at vanishing normal velocity.
    dynamic_density : float
        ``B rho_0`` (kg/m^3): the coefficient of ``Vn^2``.
    name : str
        A label for reports.
    """

    static_stress: float
    dynamic_density: float
    name: str = "custom"

    def __post_init__(self) -> None:
        for field_name in ("static_stress", "dynamic_density"):
            value = getattr(self, field_name)
            if not (math.isfinite(value) and value >= 0.0):
                raise ValueError(f"{field_name} = {value}: must be a finite number >= 0")

    @classmethod
    def from_coefficients(cls, A: float, sigma_0: float, B: float, rho_0: float, name: str = "custom") -> ResistanceLaw:
        """The law from its dimensionless coefficients and the target's ``sigma_0`` (Pa), ``rho_0`` (kg/m^3)."""
        return cls(A * sigma_0, B * rho_0, name)

    def normal_stress(self, normal_velocity: np.ndarray) -> np.ndarray:
        """``A sigma_0 + B rho_0 Vn^2`` (Pa) for ``Vn > 0`` (m/s); the caller applies separation."""
        return self.static_stress + self.dynamic_density * np.square(normal_velocity)


def locking_cavity_expansion(
    sigma_0: float, rho_0: float, locking_strain: float, name: str = "locking cavity expansion"
) -> ResistanceLaw:
    """Spherical cavity expansion in an elastic-plastic-locking soil (rigid-locking limit).

    A cavity expands at speed ``V`` into a Tresca soil of strength ``sigma_0``
    and density ``rho_0`` that locks at the volumetric strain ``eta*``: between
    the cavity ``a`` and a plastic front ``b`` the soil is locked
    (incompressible at ``rho* = rho_0 / (1 - eta*)``), so mass conservation
    fixes ``(a/b)^3 = eta*``; ahead of the front the soil is at rest with the
    elastic-limit stress ``2 sigma_0 / 3`` (elastic strains neglected).
    Integrating the radial momentum equation with ``v = V a^2/r^2`` across the
    locked region and adding the momentum jump ``rho_0 c v_b`` at the front
    (``c = V eta*^(-1/3)``, ``v_b = V eta*^(2/3)``) gives
    ``sigma_r(a) = A sigma_0 + B rho_0 V^2`` with

    * ``A = (2/3)(1 - ln eta*)`` (brief section 2), and
    * ``B = [3/2 - 2 eta*^(1/3) + eta*^(4/3)/2] / (1 - eta*) + eta*^(1/3)``.

    The brief's dynamic-cavity-expansion rows (which also use the elastic
    modulus ``E``) have ``B`` about 9 % higher (docs/effects.md).
    """
    if not (0.0 < locking_strain < 1.0):
        raise ValueError(f"locking_strain = {locking_strain}: must lie in (0, 1)")
    eta = locking_strain
    cube = eta ** (1.0 / 3.0)
    a = 2.0 / 3.0 * (1.0 - math.log(eta))
    b = (1.5 - 2.0 * cube + 0.5 * eta * cube) / (1.0 - eta) + cube
    return ResistanceLaw.from_coefficients(a, sigma_0, b, rho_0, name)


NAMED_LAWS: dict[str, ResistanceLaw] = {
    # brief section 2: Forrestal and Luk's soil, the paper's default
    "soil": ResistanceLaw.from_coefficients(1.718, 10e6, 1.227, 1860.0, "soil"),
    # spherical dynamic cavity expansion in an elastic-plastic-locking soil
    "soil_dynamic_cavity_expansion": ResistanceLaw(20.268e6, 2239.1, "soil_dynamic_cavity_expansion"),
    "softer_soil": ResistanceLaw(13.521e6, 1925.6, "softer_soil"),
}


def register_law(name: str, law: ResistanceLaw) -> None:
    """Add a law to the registry under ``name`` (scenes can then name it)."""
    if not name or not name.replace("_", "").isalnum():
        raise ValueError(f"law name {name!r}: use letters, digits and underscores")
    NAMED_LAWS[name] = law


def resistance_law(name: str) -> ResistanceLaw:
    """A named law of :data:`NAMED_LAWS`."""
    try:
        return NAMED_LAWS[name]
    except KeyError:
        raise UnknownLawError(f"law = {name!r}: must be one of {sorted(NAMED_LAWS)}") from None
