"""The target and the optional effects of a scene; each spec builds its ``fem_loads`` object."""

from __future__ import annotations

from typing import Annotated, Literal, Self

from pydantic import Discriminator, Tag, field_validator, model_validator

from fem_loads.resistance import NAMED_LAWS, ResistanceLaw, locking_cavity_expansion, resistance_law
from fem_loads.target import FreeSurface, Friction, LayeredTarget

from .base import Number, Strict, field

__all__ = [
    "LawSpec",
    "MaterialLawSpec",
    "LawChoice",
    "LayerSpec",
    "Target",
    "FrictionSpec",
    "FreeSurfaceSpec",
    "Effects",
    "build_law",
]


class LawSpec(Strict):
    """A resistance law ``sigma_n = A sigma_0 + B rho_0 Vn^2`` by its coefficients."""

    A: Number = field(ge=0.0, le=1e3, description="static coefficient")
    sigma_0: Number = field(unit="Pa", gt=0.0, le=1e11, description="target strength")
    B: Number = field(ge=0.0, le=1e3, description="dynamic coefficient")
    rho_0: Number = field(unit="kg/m^3", gt=0.0, le=1e5, description="target density")

    def build(self) -> ResistanceLaw:
        return ResistanceLaw.from_coefficients(self.A, self.sigma_0, self.B, self.rho_0)


class MaterialLawSpec(Strict):
    """A resistance law derived from material constants (docs/effects.md)."""

    model: Literal["locking_cavity_expansion"]
    sigma_0: Number = field(unit="Pa", gt=0.0, le=1e11, description="target strength")
    rho_0: Number = field(unit="kg/m^3", gt=0.0, le=1e5, description="target density")
    locking_strain: Number = field(gt=0.0, lt=1.0, description="volumetric strain eta* at locking")

    def build(self) -> ResistanceLaw:
        return locking_cavity_expansion(self.sigma_0, self.rho_0, self.locking_strain)


def _law_kind(value: object) -> str:
    if isinstance(value, str):
        return "name"
    return (
        "material"
        if isinstance(value, (dict, MaterialLawSpec))
        and "model" in (value if isinstance(value, dict) else value.model_fields_set)
        else "coefficients"
    )


LawChoice = Annotated[
    Annotated[str, Tag("name")] | Annotated[LawSpec, Tag("coefficients")] | Annotated[MaterialLawSpec, Tag("material")],
    Discriminator(_law_kind),
]
LAW_TAGS: dict[str, type[Strict]] = {"coefficients": LawSpec, "material": MaterialLawSpec}  # LawChoice's table tags


def build_law(law: str | LawSpec | MaterialLawSpec) -> ResistanceLaw:
    """The resistance law a scene names, gives by coefficients or derives from material constants."""
    return resistance_law(law) if isinstance(law, str) else law.build()


def _check_law_name(value: object) -> object:
    if isinstance(value, str) and value not in NAMED_LAWS:
        raise ValueError(
            f"unknown law {value!r}: must be one of {', '.join(sorted(NAMED_LAWS))}"
            " or a table with A, sigma_0, B and rho_0"
        )
    return value


class LayerSpec(Strict):
    """One layer of a layered target; the last layer has no thickness (it goes on forever)."""

    thickness: Number | None = field(None, unit="m", gt=0.0, le=1e4)
    law: LawChoice = field(description="a named law or a table of its coefficients")

    _known_name = field_validator("law")(classmethod(lambda cls, value: _check_law_name(value)))


class Target(Strict):
    """The half-space below the plane ``Z = 0``: homogeneous (``law``) or layered (``layers``)."""

    law: LawChoice = field("soil", description="a named law or a table of its coefficients")
    layers: list[LayerSpec] | None = field(None, description="layers from the surface down")

    _known_name = field_validator("law")(classmethod(lambda cls, value: _check_law_name(value)))

    @model_validator(mode="after")
    def _layers_consistent(self) -> Self:
        if self.layers is None:
            return self
        if "law" in self.model_fields_set:
            raise ValueError("give law (homogeneous) or layers, not both")
        if not self.layers:
            raise ValueError("layers: give at least one layer")
        if any(layer.thickness is None for layer in self.layers[:-1]):
            raise ValueError("layers: every layer but the last needs a thickness (m)")
        if self.layers[-1].thickness is not None:
            raise ValueError("layers: the last layer goes on forever; drop its thickness")
        return self

    def build(self) -> ResistanceLaw | LayeredTarget:
        """The law of a homogeneous target, or the layers."""
        if self.layers is None:
            return build_law(self.law)
        # every layer but the last has its thickness (_layers_consistent)
        thicknesses = tuple(layer.thickness for layer in self.layers[:-1] if layer.thickness is not None)
        return LayeredTarget(thicknesses, tuple(build_law(layer.law) for layer in self.layers))


class FrictionSpec(Strict):
    """Tangential stress opposite to the local slip."""

    model: Literal["none", "coulomb", "capped"] = "none"
    coefficient: Number = field(0.1, ge=0.0, le=5.0, description="mu")
    cap: Number | None = field(None, unit="Pa", gt=0.0, le=1e11, description="tau_s of the capped model")

    @model_validator(mode="after")
    def _cap_for_capped(self) -> Self:
        if self.model == "capped" and self.cap is None:
            raise ValueError("the capped model needs cap (tau_s, Pa)")
        if self.model != "capped" and self.cap is not None:
            raise ValueError('cap applies to the capped model only: drop cap or give model = "capped"')
        return self

    def build(self) -> Friction | None:
        return None if self.model == "none" else Friction(self.coefficient, self.cap)


class FreeSurfaceSpec(Strict):
    """Linear free-surface reduction of the normal stress (docs/effects.md)."""

    depth: Number = field(unit="m", gt=0.0, le=1e3, description="full resistance below this depth")
    surface_fraction: Number = field(0.0, ge=0.0, le=1.0, description="fraction of it at the surface")

    def build(self) -> FreeSurface:
        return FreeSurface(self.depth, self.surface_fraction)


class Effects(Strict):
    """Optional physical effects; each absent effect costs nothing at run time."""

    friction: FrictionSpec = FrictionSpec()
    separation: bool = field(True, description="no stress where Vn <= 0")
    contact_width: Number = field(
        0.0,
        unit="m/s",
        ge=0.0,
        le=100.0,
        description="fixed part of the normal velocity over which the stress rises from 0"
        " at Vn = 0 to the full law (docs/model.md); with contact_incidence 0"
        " too: the sharp switch",
    )
    contact_incidence: Number = field(
        0.005,
        ge=0.0,
        le=0.5,
        description="part of that width proportional to the body's speed"
        " |V| + |omega| r_max: the sine of the incidence angle over which"
        " the stress rises",
    )
    free_surface: FreeSurfaceSpec | None = None
    gravity: bool = False
    gravity_acceleration: Number = field(9.80665, unit="m/s^2", ge=0.0, le=1e3)

    @property
    def contact(self) -> dict[str, float]:
        """``contact_width`` and ``contact_incidence``, as the load and the 1-D reference take them."""
        return {"contact_width": self.contact_width, "contact_incidence": self.contact_incidence}

    @property
    def sharp_contact(self) -> bool:
        """Whether the contact factor is the sharp switch at ``Vn = 0`` (both widths zero)."""
        return self.contact_width == 0.0 and self.contact_incidence == 0.0
