"""The scene schema: what a TOML scene may say, with units and allowed ranges.

Every model forbids unknown keys and non-finite numbers.  Units are SI except
angles, which are in degrees where the name ends in ``angle``.
"""

from __future__ import annotations

from typing import Annotated, Literal

from pydantic import BaseModel, ConfigDict, Discriminator, Field, Tag, field_validator, model_validator

from fem_loads.resistance import NAMED_LAWS

__all__ = ["Scene", "Projectile", "Target", "LayerSpec", "Effects", "FrictionSpec", "FreeSurfaceSpec",
           "Impact", "Numerics", "Outputs",
           "OgiveNoseSpec", "ConeNoseSpec", "InteriorSpec", "CounterweightSpec",
           "MassPropertiesSpec", "LawSpec"]


def _field(default=..., *, unit: str = "", description: str = "", **limits):
    """A field with its unit recorded for error messages."""
    extra = {"unit": unit} if unit else None
    return Field(default, description=description, json_schema_extra=extra, **limits)


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_default=True)


class OgiveNoseSpec(_Strict):
    """Tangent ogive nose."""

    shape: Literal["ogive"]
    crh: float = _field(unit="calibres", ge=0.5, le=100.0,
                        description="caliber-radius-head: ogive radius in diameters")


class ConeNoseSpec(_Strict):
    """Conical nose."""

    shape: Literal["cone"]
    half_angle: float = _field(unit="deg", gt=0.0, lt=90.0, description="cone half-angle")


class SecantOgiveNoseSpec(_Strict):
    """Secant ogive: an arc of ``crh`` diameters through the tip and the shoulder."""

    shape: Literal["secant_ogive"]
    crh: float = _field(unit="calibres", gt=0.0, le=100.0, description="ogive radius in diameters")
    length: float = _field(unit="calibres", gt=0.0, le=50.0, description="nose length in diameters")


class HemisphereNoseSpec(_Strict):
    """Hemispherical nose (a tangent ogive of CRH 0.5)."""

    shape: Literal["hemisphere"]


class BluntNoseSpec(_Strict):
    """Flat-tipped nose: a tangent ogive of ``crh`` truncated by a flat face of radius ``flat_radius``."""

    shape: Literal["blunt"]
    crh: float = _field(unit="calibres", ge=0.5, le=100.0)
    flat_radius: float = _field(unit="m", gt=0.0, le=5.0, description="radius of the flat front face")


NoseSpec = Annotated[OgiveNoseSpec | ConeNoseSpec | SecantOgiveNoseSpec | HemisphereNoseSpec | BluntNoseSpec,
                     Field(discriminator="shape")]


class InteriorSpec(_Strict):
    """A cavity a wall thickness inside the outer profile."""

    wall_thickness: float = _field(unit="m", gt=0.0, le=10.0, description="radial wall thickness")
    tail_thickness: float = _field(unit="m", gt=0.0, le=100.0, description="tail plate thickness")


class CounterweightSpec(_Strict):
    """A counterweight filling the cavity between two cross-sections.

    Give ``start`` and ``end`` (m from the tip), or neither: then the
    projectile's ``mass`` and centre of mass place it.
    """

    density: float = _field(18000.0, unit="kg/m^3", gt=0.0, le=1e5)
    start: float | None = _field(None, unit="m", ge=0.0, le=100.0, description="from the nose tip")
    end: float | None = _field(None, unit="m", gt=0.0, le=100.0, description="from the nose tip")

    @model_validator(mode="after")
    def _both_or_neither(self):
        if (self.start is None) != (self.end is None):
            raise ValueError("give both start and end (m from the tip), or neither")
        if self.start is not None and not self.start < self.end:
            raise ValueError(f"start = {self.start} must be less than end = {self.end}")
        return self


class MassPropertiesSpec(_Strict):
    """Mass properties given directly instead of integrated over the mesh."""

    mass: float = _field(unit="kg", gt=0.0, le=1e6)
    centre_of_mass: float = _field(unit="m", gt=0.0, le=100.0, description="from the nose tip")
    axial_inertia: float = _field(unit="kg m^2", gt=0.0, le=1e9)
    transverse_inertia: float = _field(unit="kg m^2", gt=0.0, le=1e9)


class Projectile(_Strict):
    """An axisymmetric projectile: nose, cylindrical shank and flat tail."""

    name: str = ""
    diameter: float = _field(unit="m", gt=0.0, le=10.0)
    length: float = _field(unit="m", gt=0.0, le=100.0, description="nose tip to tail")
    nose: NoseSpec
    body_density: float | None = _field(None, unit="kg/m^3", gt=0.0, le=1e5)
    mass: float | None = _field(None, unit="kg", gt=0.0, le=1e6)
    centre_of_mass: float | None = _field(None, unit="m", gt=0.0, le=100.0,
                                          description="target centre of mass, from the nose tip")
    centre_of_mass_ratio: float | None = _field(None, unit="Lc/L", gt=0.0, lt=1.0,
                                                description="target centre of mass over length")
    interior: InteriorSpec | None = None
    counterweight: CounterweightSpec | None = None
    mass_properties: MassPropertiesSpec | None = None
    transverse_inertia_scale: float = _field(1.0, unit="", gt=0.0, le=100.0,
                                             description="factor on both transverse moments of inertia")

    @model_validator(mode="after")
    def _consistent(self):
        wants_centre = self.centre_of_mass is not None or self.centre_of_mass_ratio is not None
        if self.centre_of_mass is not None and self.centre_of_mass_ratio is not None:
            raise ValueError("give centre_of_mass or centre_of_mass_ratio, not both")
        if self.counterweight is not None and self.interior is None:
            raise ValueError("counterweight needs an interior (a cavity to fill)")
        if self.mass_properties is not None:
            if self.mass is not None or wants_centre:
                raise ValueError("mass_properties sets mass and centre of mass itself:"
                                 " drop mass, centre_of_mass and centre_of_mass_ratio")
            return self
        placing = self.counterweight is not None and self.counterweight.start is None
        if placing:
            if self.mass is None or not wants_centre:
                raise ValueError("a counterweight without start and end needs mass and"
                                 " centre_of_mass (or centre_of_mass_ratio) to place it")
            return self
        if wants_centre:
            raise ValueError("centre_of_mass places a counterweight that has no start and end;"
                             " to set it directly give mass_properties")
        if self.mass is not None and self.counterweight is not None:
            raise ValueError("with a placed counterweight the mass follows from the densities: drop mass")
        if self.mass is not None and self.body_density is not None:
            raise ValueError("give mass or body_density, not both")
        return self

    @property
    def centre_target(self) -> float | None:
        """Target centre of mass from the tip (m), if any."""
        if self.centre_of_mass_ratio is not None:
            return self.centre_of_mass_ratio * self.length
        return self.centre_of_mass


class LawSpec(_Strict):
    """A resistance law ``sigma_n = A sigma_0 + B rho_0 Vn^2`` by its coefficients."""

    A: float = _field(ge=0.0, le=1e3, description="static coefficient")
    sigma_0: float = _field(unit="Pa", gt=0.0, le=1e11, description="target strength")
    B: float = _field(ge=0.0, le=1e3, description="dynamic coefficient")
    rho_0: float = _field(unit="kg/m^3", gt=0.0, le=1e5, description="target density")


class MaterialLawSpec(_Strict):
    """A resistance law derived from material constants (docs/effects.md)."""

    model: Literal["locking_cavity_expansion"]
    sigma_0: float = _field(unit="Pa", gt=0.0, le=1e11, description="target strength")
    rho_0: float = _field(unit="kg/m^3", gt=0.0, le=1e5, description="target density")
    locking_strain: float = _field(gt=0.0, lt=1.0, description="volumetric strain eta* at locking")


def _law_kind(value) -> str:
    if isinstance(value, str):
        return "name"
    return "material" if isinstance(value, (dict, MaterialLawSpec)) and "model" in (
        value if isinstance(value, dict) else value.model_fields_set) else "coefficients"


LawChoice = Annotated[
    Annotated[str, Tag("name")] | Annotated[LawSpec, Tag("coefficients")]
    | Annotated[MaterialLawSpec, Tag("material")],
    Discriminator(_law_kind),
]


def _check_law_name(value):
    if isinstance(value, str) and value not in NAMED_LAWS:
        raise ValueError(f"unknown law {value!r}: must be one of {', '.join(sorted(NAMED_LAWS))}"
                         " or a table with A, sigma_0, B and rho_0")
    return value


class LayerSpec(_Strict):
    """One layer of a layered target; the last layer has no thickness (it goes on forever)."""

    thickness: float | None = _field(None, unit="m", gt=0.0, le=1e4)
    law: LawChoice = _field(description="a named law or a table of its coefficients")

    _known_name = field_validator("law")(classmethod(lambda cls, value: _check_law_name(value)))


class Target(_Strict):
    """The half-space below the plane ``Z = 0``: homogeneous (``law``) or layered (``layers``)."""

    law: LawChoice = _field("soil", description="a named law or a table of its coefficients")
    layers: list[LayerSpec] | None = _field(None, description="layers from the surface down")

    _known_name = field_validator("law")(classmethod(lambda cls, value: _check_law_name(value)))

    @model_validator(mode="after")
    def _layers_consistent(self):
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


class FrictionSpec(_Strict):
    """Tangential stress opposite to the local slip."""

    model: Literal["none", "coulomb", "capped"] = "none"
    coefficient: float = _field(0.1, ge=0.0, le=5.0, description="mu")
    cap: float | None = _field(None, unit="Pa", gt=0.0, le=1e11, description="tau_s of the capped model")

    @model_validator(mode="after")
    def _cap_for_capped(self):
        if self.model == "capped" and self.cap is None:
            raise ValueError("the capped model needs cap (tau_s, Pa)")
        if self.model != "capped" and self.cap is not None:
            raise ValueError("cap applies to the capped model only")
        return self


class FreeSurfaceSpec(_Strict):
    """Linear free-surface reduction of the normal stress (docs/effects.md)."""

    depth: float = _field(unit="m", gt=0.0, le=1e3, description="full resistance below this depth")
    surface_fraction: float = _field(0.0, ge=0.0, le=1.0, description="fraction of it at the surface")


class Effects(_Strict):
    """Optional physical effects; each absent effect costs nothing at run time."""

    friction: FrictionSpec = FrictionSpec()
    separation: bool = _field(True, description="no stress where Vn <= 0")
    free_surface: FreeSurfaceSpec | None = None
    gravity: bool = False
    gravity_acceleration: float = _field(9.80665, unit="m/s^2", ge=0.0, le=1e3)


class Impact(_Strict):
    """Initial conditions; the tip (or, at grazing incidence, the lowest point) touches the surface."""

    speed: float = _field(unit="m/s", gt=0.0, le=1e4)
    oblique_angle: float = _field(0.0, unit="deg", gt=-90.0, lt=90.0,
                                  description="velocity from the target normal")
    attack_angle: float = _field(0.0, unit="deg", ge=-90.0, le=90.0,
                                 description="axis from the velocity, in the vertical plane")
    yaw_angle: float = _field(0.0, unit="deg", gt=-90.0, lt=90.0,
                              description="axis out of the vertical plane")
    angular_velocity: tuple[float, float, float] = _field(
        (0.0, 0.0, 0.0), unit="rad/s",
        description="body frame: x along the axis, y normal to the vertical plane")

    @model_validator(mode="after")
    def _bounded_spin(self):
        if max(abs(w) for w in self.angular_velocity) > 1e5:
            raise ValueError("angular_velocity: each component must lie in [-1e5, 1e5] rad/s")
        return self


class Numerics(_Strict):
    """Discretisation and integration settings."""

    mesh_size: float = _field(unit="m", gt=0.0, le=10.0, description="target element size")
    geometry_order: Literal[1, 2] = 2
    normals: Literal["exact", "mesh"] = "exact"
    quadrature_order: int = _field(2, ge=1, le=10, description="degree exact on each facet")
    integrator: Literal["rk4", "dopri54"] = "rk4"
    time_step: float = _field(2e-5, unit="s", gt=0.0, le=1e-2, description="fixed step (rk4)")
    rtol: float = _field(1e-6, gt=0.0, lt=1.0, description="relative tolerance (dopri54)")
    time_limit: float = _field(1.0, unit="s", gt=0.0, le=100.0)
    stop_speed: float = _field(0.5, unit="m/s", gt=0.0, le=1e3,
                               description="the run ends when the speed falls below this")
    normal_velocity_guard: float = _field(1e-9, ge=0.0, le=1e-3,
                                          description="relative guard on Vn = 0")
    energy_guard: bool = _field(True, description="retake shorter any step that gains kinetic energy")


class Outputs(_Strict):
    """What a run writes with --out."""

    history: bool = True
    history_every: int = _field(1, ge=1, le=1_000_000, description="keep every n-th step")


class Scene(_Strict):
    """A complete scene: projectile, target, impact, numerics and outputs."""

    name: str = ""
    description: str = ""
    projectile: Projectile
    target: Target = Target()
    effects: Effects = Effects()
    impact: Impact
    numerics: Numerics
    outputs: Outputs = Outputs()
