"""Cavity-expansion resistance laws ``sigma_n = A sigma_0 + B rho_0 Vn^2``."""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

__all__ = ["ResistanceLaw", "NAMED_LAWS", "resistance_law"]


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
    def from_coefficients(cls, A: float, sigma_0: float, B: float, rho_0: float,
                          name: str = "custom") -> ResistanceLaw:
        """The law from its dimensionless coefficients and the target's ``sigma_0`` (Pa), ``rho_0`` (kg/m^3)."""
        return cls(A * sigma_0, B * rho_0, name)

    def normal_stress(self, normal_velocity: np.ndarray) -> np.ndarray:
        """``A sigma_0 + B rho_0 Vn^2`` (Pa) for ``Vn > 0`` (m/s); the caller applies separation."""
        return self.static_stress + self.dynamic_density * np.square(normal_velocity)


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
        raise ValueError(f"law = {name!r}: must be one of {sorted(NAMED_LAWS)}") from None
