"""The scene schema: what a TOML scene may say, with units and allowed ranges.

Every model forbids unknown keys and non-finite numbers.  Units are SI except
angles, which are in degrees where the name ends in ``angle``.
"""

from __future__ import annotations

import math
from typing import Annotated, Literal

from pydantic import BaseModel, BeforeValidator, ConfigDict, Discriminator, Field, Tag, field_validator, model_validator
from pydantic_core import PydanticCustomError

from fem_loads.resistance import NAMED_LAWS

__all__ = ["Scene", "Projectile", "Target", "LayerSpec", "Effects", "FrictionSpec", "FreeSurfaceSpec",
           "Impact", "Numerics", "Outputs",
           "OgiveNoseSpec", "ConeNoseSpec", "InteriorSpec", "CounterweightSpec",
           "MassPropertiesSpec", "LawSpec"]


MAX_STEPS = 5_000_000  # dynamics.simulate's max_steps: no run takes more than time_limit / time_step
MAX_MESH_CELLS = 2e6  # cells of mesh_size^3 in the projectile's bounding cylinder (about 1e7 tetrahedra)
# lightest mean density (kg/m^3) over the bounding cylinder: far below any hard projectile (balsa is 150);
# a 1e-300 kg projectile overflowed the first step (math domain error)
MIN_MEAN_DENSITY = 100.0


def _field(default=..., *, unit: str = "", description: str = "", **limits):
    """A field with its unit recorded for error messages."""
    extra = {"unit": unit} if unit else None
    return Field(default, description=description, json_schema_extra=extra, **limits)


def _not_boolean(value):
    """``true`` is not a number (pydantic would read it as 1)."""
    if isinstance(value, bool):
        raise PydanticCustomError("number_type", "input should be a number, not true or false")
    return value


def _one_line(value):
    """Labels print as one line: no newlines, tabs, escapes or other control characters."""
    if isinstance(value, str) and not value.isprintable():
        raise PydanticCustomError("text_type", "input should be one line of printable text"
                                  " (no newlines, tabs or control characters)")
    return value


Number = Annotated[float, BeforeValidator(_not_boolean)]
Whole = Annotated[int, BeforeValidator(_not_boolean)]
Label = Annotated[str, BeforeValidator(_one_line)]


class _Strict(BaseModel):
    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, validate_default=True)


class OgiveNoseSpec(_Strict):
    """Tangent ogive nose."""

    shape: Literal["ogive"]
    crh: Number = _field(unit="calibres", ge=0.5, le=100.0,
                        description="caliber-radius-head: ogive radius in diameters")


class ConeNoseSpec(_Strict):
    """Conical nose."""

    shape: Literal["cone"]
    half_angle: Number = _field(unit="deg", gt=0.0, lt=90.0, description="cone half-angle")


class SecantOgiveNoseSpec(_Strict):
    """Secant ogive: an arc of ``crh`` diameters through the tip and the shoulder."""

    shape: Literal["secant_ogive"]
    crh: Number = _field(unit="calibres", gt=0.0, le=100.0, description="ogive radius in diameters")
    length: Number = _field(unit="calibres", gt=0.0, le=50.0, description="nose length in diameters")


class HemisphereNoseSpec(_Strict):
    """Hemispherical nose (a tangent ogive of CRH 0.5)."""

    shape: Literal["hemisphere"]


class BluntNoseSpec(_Strict):
    """Flat-tipped nose: a tangent ogive of ``crh`` truncated by a flat face of radius ``flat_radius``."""

    shape: Literal["blunt"]
    crh: Number = _field(unit="calibres", ge=0.5, le=100.0)
    flat_radius: Number = _field(unit="m", gt=0.0, le=5.0, description="radius of the flat front face")


NoseSpec = Annotated[OgiveNoseSpec | ConeNoseSpec | SecantOgiveNoseSpec | HemisphereNoseSpec | BluntNoseSpec,
                     Field(discriminator="shape")]


class InteriorSpec(_Strict):
    """A cavity a wall thickness inside the outer profile."""

    wall_thickness: Number = _field(unit="m", gt=0.0, le=10.0, description="radial wall thickness")
    tail_thickness: Number = _field(unit="m", gt=0.0, le=100.0, description="tail plate thickness")


class CounterweightSpec(_Strict):
    """A counterweight filling the cavity between two cross-sections.

    Give ``start`` and ``end`` (m from the tip), or neither: then the
    projectile's ``mass`` and centre of mass place it.
    """

    density: Number = _field(18000.0, unit="kg/m^3", gt=0.0, le=1e5)
    start: Number | None = _field(None, unit="m", ge=0.0, le=100.0, description="from the nose tip")
    end: Number | None = _field(None, unit="m", gt=0.0, le=100.0, description="from the nose tip")

    @model_validator(mode="after")
    def _both_or_neither(self):
        if (self.start is None) != (self.end is None):
            raise ValueError("give both start and end (m from the tip), or neither")
        if self.start is not None and not self.start < self.end:
            raise ValueError(f"start = {self.start} must be less than end = {self.end}")
        return self


class MassPropertiesSpec(_Strict):
    """Mass properties given directly instead of integrated over the mesh."""

    mass: Number = _field(unit="kg", gt=0.0, le=1e6)
    centre_of_mass: Number = _field(unit="m", gt=0.0, le=100.0, description="from the nose tip")
    axial_inertia: Number = _field(unit="kg m^2", gt=0.0, le=1e9)
    transverse_inertia: Number = _field(unit="kg m^2", gt=0.0, le=1e9)

    @model_validator(mode="after")
    def _rigid_body(self):
        # I_axial = int (y^2 + z^2) dm <= I_y + I_z = 2 I_transverse for every rigid body
        if self.axial_inertia > 2.0 * self.transverse_inertia:
            raise ValueError(f"axial_inertia = {self.axial_inertia:g}: more than twice transverse_inertia ="
                             f" {self.transverse_inertia:g}, which no rigid body has (allowed: axial_inertia"
                             " <= 2 transverse_inertia)")
        return self


class Projectile(_Strict):
    """An axisymmetric projectile: nose, cylindrical shank and flat tail."""

    name: Label = ""
    diameter: Number = _field(unit="m", gt=0.0, le=10.0)
    length: Number = _field(unit="m", gt=0.0, le=100.0, description="nose tip to tail")
    nose: NoseSpec
    body_density: Number | None = _field(None, unit="kg/m^3", gt=0.0, le=1e5)
    mass: Number | None = _field(None, unit="kg", gt=0.0, le=1e6)
    centre_of_mass: Number | None = _field(None, unit="m", gt=0.0, le=100.0,
                                          description="target centre of mass, from the nose tip")
    centre_of_mass_ratio: Number | None = _field(None, unit="Lc/L", gt=0.0, lt=1.0,
                                                description="target centre of mass over length")
    interior: InteriorSpec | None = None
    counterweight: CounterweightSpec | None = None
    mass_properties: MassPropertiesSpec | None = None
    transverse_inertia_scale: Number = _field(1.0, unit="", gt=0.0, le=100.0,
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

    @model_validator(mode="after")
    def _buildable(self):
        """The mesh room's own checks of the shape (nose shorter than the body, cavity inside the wall, ...),
        made here so that they fail before any meshing, naming the field."""
        from mesh import Interior, Profile, ProjectileGeometry

        from .runner import nose_of

        profile = Profile(self.diameter, self.length, nose_of(self.nose))
        interior = None
        if self.interior is not None:
            interior = Interior(self.interior.wall_thickness, self.interior.tail_thickness)
        span = None
        if self.counterweight is not None and self.counterweight.start is not None:
            span = (self.counterweight.start, self.counterweight.end)
        ProjectileGeometry(profile, interior, span)
        mass = self.mass_properties.mass if self.mass_properties is not None else self.mass
        lightest = MIN_MEAN_DENSITY * 0.25 * math.pi * self.diameter ** 2 * self.length
        if mass is not None and mass < lightest:
            field = "mass_properties.mass" if self.mass_properties is not None else "mass"
            raise ValueError(f"{field} = {mass:g}: lighter than {MIN_MEAN_DENSITY:g} kg/m^3 over the bounding"
                             f" cylinder (allowed: {field} >= {lightest:.3g} kg for this diameter and length)")
        return self

    @property
    def centre_target(self) -> float | None:
        """Target centre of mass from the tip (m), if any."""
        if self.centre_of_mass_ratio is not None:
            return self.centre_of_mass_ratio * self.length
        return self.centre_of_mass


class LawSpec(_Strict):
    """A resistance law ``sigma_n = A sigma_0 + B rho_0 Vn^2`` by its coefficients."""

    A: Number = _field(ge=0.0, le=1e3, description="static coefficient")
    sigma_0: Number = _field(unit="Pa", gt=0.0, le=1e11, description="target strength")
    B: Number = _field(ge=0.0, le=1e3, description="dynamic coefficient")
    rho_0: Number = _field(unit="kg/m^3", gt=0.0, le=1e5, description="target density")


class MaterialLawSpec(_Strict):
    """A resistance law derived from material constants (docs/effects.md)."""

    model: Literal["locking_cavity_expansion"]
    sigma_0: Number = _field(unit="Pa", gt=0.0, le=1e11, description="target strength")
    rho_0: Number = _field(unit="kg/m^3", gt=0.0, le=1e5, description="target density")
    locking_strain: Number = _field(gt=0.0, lt=1.0, description="volumetric strain eta* at locking")


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

    thickness: Number | None = _field(None, unit="m", gt=0.0, le=1e4)
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
    coefficient: Number = _field(0.1, ge=0.0, le=5.0, description="mu")
    cap: Number | None = _field(None, unit="Pa", gt=0.0, le=1e11, description="tau_s of the capped model")

    @model_validator(mode="after")
    def _cap_for_capped(self):
        if self.model == "capped" and self.cap is None:
            raise ValueError("the capped model needs cap (tau_s, Pa)")
        if self.model != "capped" and self.cap is not None:
            raise ValueError("cap applies to the capped model only: drop cap or give model = \"capped\"")
        return self


class FreeSurfaceSpec(_Strict):
    """Linear free-surface reduction of the normal stress (docs/effects.md)."""

    depth: Number = _field(unit="m", gt=0.0, le=1e3, description="full resistance below this depth")
    surface_fraction: Number = _field(0.0, ge=0.0, le=1.0, description="fraction of it at the surface")


class Effects(_Strict):
    """Optional physical effects; each absent effect costs nothing at run time."""

    friction: FrictionSpec = FrictionSpec()
    separation: bool = _field(True, description="no stress where Vn <= 0")
    free_surface: FreeSurfaceSpec | None = None
    gravity: bool = False
    gravity_acceleration: Number = _field(9.80665, unit="m/s^2", ge=0.0, le=1e3)


class Impact(_Strict):
    """Initial conditions; the tip (or, at grazing incidence, the lowest point) touches the surface."""

    speed: Number = _field(unit="m/s", gt=0.0, le=1e4)
    oblique_angle: Number = _field(0.0, unit="deg", gt=-90.0, lt=90.0,
                                  description="velocity from the target normal")
    attack_angle: Number = _field(0.0, unit="deg", ge=-90.0, le=90.0,
                                 description="axis from the velocity, in the vertical plane")
    yaw_angle: Number = _field(0.0, unit="deg", gt=-90.0, lt=90.0,
                              description="axis out of the vertical plane")
    angular_velocity: tuple[Number, Number, Number] = _field(
        (0.0, 0.0, 0.0), unit="rad/s",
        description="body frame: x along the axis, y normal to the vertical plane")

    @model_validator(mode="after")
    def _bounded_spin(self):
        if max(abs(w) for w in self.angular_velocity) > 1e5:
            raise ValueError("angular_velocity: each component must lie in [-1e5, 1e5] rad/s")
        return self


class Numerics(_Strict):
    """Discretisation and integration settings."""

    mesh_size: Number = _field(unit="m", gt=0.0, le=10.0, description="target element size")
    geometry_order: Annotated[Literal[1, 2], BeforeValidator(_not_boolean)] = 2
    normals: Literal["exact", "mesh"] = "exact"
    quadrature_order: Whole = _field(2, ge=1, le=10, description="degree exact on each facet")
    integrator: Literal["rk4", "dopri54"] = "rk4"
    time_step: Number = _field(2e-5, unit="s", gt=0.0, le=1e-2,
                               description="fixed step (rk4); the error control shortens no step below it (dopri54)")
    rtol: Number = _field(1e-6, gt=0.0, lt=1.0, description="relative tolerance (dopri54)")
    time_limit: Number = _field(1.0, unit="s", gt=0.0, le=100.0)
    stop_speed: Number = _field(0.5, unit="m/s", gt=0.0, le=1e3,
                               description="the run ends when the speed falls below this")
    normal_velocity_guard: Number = _field(1e-9, ge=0.0, le=1e-3,
                                          description="relative guard on Vn = 0")
    energy_guard: bool = _field(True, description="retake shorter any step that gains kinetic energy")

    @model_validator(mode="after")
    def _reachable_time_limit(self):
        # rk4 steps by time_step, and dopri54 shortens no step below it
        if self.time_limit / self.time_step > MAX_STEPS:
            raise ValueError(f"time_step = {self.time_step:g}: {self.time_limit / self.time_step:.3g} steps to reach"
                             f" time_limit = {self.time_limit:g} s (allowed: time_limit / time_step <= {MAX_STEPS:g};"
                             " shorten time_limit or lengthen time_step)")
        return self


class Outputs(_Strict):
    """What a run writes with --out."""

    history: bool = True
    history_every: Whole = _field(1, ge=1, le=1_000_000, description="keep every n-th step")


class Scene(_Strict):
    """A complete scene: projectile, target, impact, numerics and outputs."""

    name: Label = ""
    description: Label = ""
    projectile: Projectile
    target: Target = Target()
    effects: Effects = Effects()
    impact: Impact
    numerics: Numerics
    outputs: Outputs = Outputs()

    @model_validator(mode="after")
    def _meshable(self):
        # a guard against typos (1e-5 for 1e-2) that would mesh forever: the studies' finest mesh has ~1e5 cells
        p, size = self.projectile, self.numerics.mesh_size
        finest = (0.25 * math.pi * p.diameter ** 2 * p.length / MAX_MESH_CELLS) ** (1 / 3)
        if size < finest:
            raise ValueError(f"numerics.mesh_size = {size:g}: too fine for this projectile (allowed: numerics.mesh_size"
                             f" >= {finest:.3g} m, at most {MAX_MESH_CELLS:g} cells of mesh_size^3 in"
                             " pi/4 diameter^2 length)")
        if size > p.diameter:  # describes nothing of the cross-section; gmsh fails on such meshes (HXT, Newton)
            raise ValueError(f"numerics.mesh_size = {size:g}: coarser than the projectile (allowed: numerics.mesh_size"
                             f" <= projectile.diameter = {p.diameter:g} m)")
        return self
