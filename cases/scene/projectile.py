"""The projectile of a scene: nose, body, interior, counterweight and mass; each spec builds its mesh-room object."""

from __future__ import annotations

import math
from dataclasses import replace
from typing import TYPE_CHECKING, Annotated, Literal, Self

from pydantic import Field, model_validator

from mesh import (
    BODY,
    COUNTERWEIGHT,
    BluntOgiveNose,
    ConeNose,
    Interior,
    OgiveNose,
    Profile,
    ProfileBody,
    ProfileNose,
    ProjectileGeometry,
    SecantOgiveNose,
    place_counterweight,
)
from mesh.imported import MATERIAL_BASE, FileGeometry

from .base import Label, Number, Strict, field
from .geometry_file import GeometryFileSpec
from .plausible import BODY_LENGTH, DENSITY, DIAMETER, POSITION, WALL, number, slip_hint

if TYPE_CHECKING:
    from fem_loads import MassProperties

__all__ = [
    "Projectile",
    "GeometryFileSpec",
    "NoseSpec",
    "OgiveNoseSpec",
    "ConeNoseSpec",
    "SecantOgiveNoseSpec",
    "HemisphereNoseSpec",
    "BluntNoseSpec",
    "ProfileNoseSpec",
    "BodySpec",
    "InteriorSpec",
    "CounterweightSpec",
    "MassPropertiesSpec",
    "DEFAULT_BODY_DENSITY",
    "MIN_MEAN_DENSITY",
]

DEFAULT_BODY_DENSITY = 7850.0  # steel (kg/m^3)
# lightest mean density (kg/m^3) over the bounding cylinder: far below any hard projectile (balsa is 150);
# a 1e-300 kg projectile overflowed the first step (math domain error)
MIN_MEAN_DENSITY = 100.0
#: how a mass is held to the body's size (Projectile._buildable), said in its fields' descriptions
MASS_RANGE = (
    f"; over the bounding cylinder of an analytic body, a mean density of {MIN_MEAN_DENSITY:g} to"
    f" {DENSITY.high:g} kg/m^3 (the densest solid)"
)


class OgiveNoseSpec(Strict):
    """Tangent ogive nose."""

    shape: Literal["ogive"]
    crh: Number = field(unit="calibres", ge=0.5, le=100.0, description="caliber-radius-head: ogive radius in diameters")

    def build(self) -> OgiveNose:
        return OgiveNose(self.crh)


class ConeNoseSpec(Strict):
    """Conical nose."""

    shape: Literal["cone"]
    half_angle: Number = field(unit="deg", gt=0.0, lt=90.0, description="cone half-angle")

    def build(self) -> ConeNose:
        return ConeNose(self.half_angle)


class SecantOgiveNoseSpec(Strict):
    """Secant ogive: an arc of ``crh`` diameters through the tip and the shoulder."""

    shape: Literal["secant_ogive"]
    crh: Number = field(unit="calibres", gt=0.0, le=100.0, description="ogive radius in diameters")
    length: Number = field(unit="calibres", gt=0.0, le=50.0, description="nose length in diameters")

    def build(self) -> SecantOgiveNose:
        return SecantOgiveNose(self.crh, self.length)


class HemisphereNoseSpec(Strict):
    """Hemispherical nose (a tangent ogive of CRH 0.5)."""

    shape: Literal["hemisphere"]

    def build(self) -> OgiveNose:
        return OgiveNose(0.5)


class BluntNoseSpec(Strict):
    """Flat-tipped nose: a tangent ogive of ``crh`` truncated by a flat face of radius ``flat_radius``."""

    shape: Literal["blunt"]
    crh: Number = field(unit="calibres", ge=0.5, le=100.0)
    flat_radius: Number = field(unit="m", gt=0.0, le=5.0, plausible=WALL, description="radius of the flat front face")

    def build(self) -> BluntOgiveNose:
        return BluntOgiveNose(self.crh, self.flat_radius)


MAX_PROFILE_POINTS = 1000
Coordinate = Annotated[Number, Field(ge=0.0, le=100.0)]


class ProfileNoseSpec(Strict):
    """A measured nose: ``[x, r]`` points (m) of its half-profile, tip first, joined by a
    shape-preserving cubic (mesh.measured); the last point meets the shank (``r = diameter / 2``)."""

    shape: Literal["profile"]
    points: list[tuple[Coordinate, Coordinate]] = field(
        unit="m",
        min_length=3,
        max_length=MAX_PROFILE_POINTS,
        description="[x, r] from the tip: x strictly increasing from 0, r non-decreasing from 0 to the shank radius",
    )

    def build(self) -> ProfileNose:
        return ProfileNose(tuple(self.points))


class BodySpec(Strict):
    """A measured body behind the nose (a boat tail, a flare): ``[x, r]`` points (m from the tip) from where it
    leaves the shank's cylinder (``r = diameter / 2``) to the tail (``x = length``), joined by the same
    shape-preserving cubic as a measured nose (mesh.measured)."""

    points: list[tuple[Coordinate, Coordinate]] = field(
        unit="m",
        min_length=2,
        max_length=MAX_PROFILE_POINTS,
        description="[x, r] from the tip: x strictly increasing from the shank (r = diameter / 2) to the tail"
        " (x = length), r > 0",
    )

    def build(self) -> ProfileBody:
        return ProfileBody(tuple(self.points))


NOSE_SPECS = (OgiveNoseSpec, ConeNoseSpec, SecantOgiveNoseSpec, HemisphereNoseSpec, BluntNoseSpec, ProfileNoseSpec)
NoseSpec = Annotated[
    OgiveNoseSpec | ConeNoseSpec | SecantOgiveNoseSpec | HemisphereNoseSpec | BluntNoseSpec | ProfileNoseSpec,
    Field(discriminator="shape"),
]


class InteriorSpec(Strict):
    """A cavity a wall thickness inside the outer profile."""

    wall_thickness: Number = field(unit="m", gt=0.0, le=10.0, plausible=WALL, description="radial wall thickness")
    tail_thickness: Number = field(unit="m", gt=0.0, le=100.0, plausible=WALL, description="tail plate thickness")

    def build(self) -> Interior:
        return Interior(self.wall_thickness, self.tail_thickness)


class CounterweightSpec(Strict):
    """A counterweight filling the cavity between two cross-sections.

    Give ``start`` and ``end`` (m from the tip), or neither: then the
    projectile's ``mass`` and centre of mass place it.
    """

    density: Number = field(
        18000.0, unit="kg/m^3", gt=0.0, le=1e5, plausible=DENSITY, description="of the counterweight"
    )
    start: Number | None = field(
        None, unit="m", ge=0.0, le=100.0, plausible=replace(POSITION, zero=True), description="from the nose tip"
    )
    end: Number | None = field(None, unit="m", gt=0.0, le=100.0, plausible=POSITION, description="from the nose tip")

    @model_validator(mode="after")
    def _both_or_neither(self) -> Self:
        if (self.start is None) != (self.end is None):
            raise ValueError("give both start and end (m from the tip), or neither")
        if self.start is not None and self.end is not None and not self.start < self.end:
            raise ValueError(f"start = {self.start} must be less than end = {self.end}")
        return self


class MassPropertiesSpec(Strict):
    """Mass properties given directly instead of integrated over the mesh."""

    # the mass is held to the body's size by Projectile._buildable (a mean density a solid can have)
    mass: Number = field(unit="kg", gt=0.0, le=1e6, description="of the whole projectile" + MASS_RANGE)
    centre_of_mass: Number = field(unit="m", gt=0.0, le=100.0, plausible=POSITION, description="from the nose tip")
    axial_inertia: Number = field(unit="kg m^2", gt=0.0, le=1e9, description="about the axis")
    transverse_inertia: Number = field(
        unit="kg m^2", gt=0.0, le=1e9, description="about an axis across the body through the centre of mass"
    )

    @classmethod
    def of(cls, mass: MassProperties) -> Self:
        """The given properties of a body's integrated ones (a body of revolution's: axial and transverse)."""
        return cls(
            mass=mass.mass,
            centre_of_mass=mass.centre_from_tip,
            axial_inertia=mass.axial_inertia,
            transverse_inertia=mass.transverse_inertia,
        )

    @model_validator(mode="after")
    def _rigid_body(self) -> Self:
        # I_axial = int (y^2 + z^2) dm <= I_y + I_z = 2 I_transverse for every rigid body
        if self.axial_inertia > 2.0 * self.transverse_inertia:
            raise ValueError(
                f"axial_inertia = {self.axial_inertia:g}: more than twice transverse_inertia ="
                f" {self.transverse_inertia:g}, which no rigid body has (allowed: axial_inertia"
                " <= 2 transverse_inertia)"
            )
        return self


Density = Annotated[Number, Field(gt=0.0, le=1e5)]


class Projectile(Strict):
    """A projectile: an axisymmetric nose, cylindrical shank and flat tail, or any body read from a file."""

    name: Label = field("", description="printed with the summary")
    diameter: Number | None = field(None, unit="m", gt=0.0, le=10.0, plausible=DIAMETER, description="of the shank")
    length: Number | None = field(
        None, unit="m", gt=0.0, le=100.0, plausible=BODY_LENGTH, description="nose tip to tail"
    )
    nose: NoseSpec | None = field(None, description="the nose's shape: one of the tables below")
    body: BodySpec | None = field(
        None, description="a measured body behind the nose (a boat tail, a flare); default: the cylinder to the tail"
    )
    geometry: GeometryFileSpec | None = None
    materials: dict[Label, Density] | None = field(
        None, unit="kg/m^3", plausible=DENSITY, description="density of a file's named solids or groups"
    )
    body_density: Number | None = field(
        None, unit="kg/m^3", gt=0.0, le=1e5, plausible=DENSITY, description="of the case (with a counterweight)"
    )
    # the mass is held to the body's size by _buildable (a mean density a solid can have), not to a range
    mass: Number | None = field(
        None,
        unit="kg",
        gt=0.0,
        le=1e6,
        description="alone: a homogeneous body of this mass; with a counterweight: the whole" + MASS_RANGE,
    )
    centre_of_mass: Number | None = field(
        None,
        unit="m",
        gt=0.0,
        le=100.0,
        plausible=POSITION,
        description="the centre of mass to place the counterweight for, from the nose tip",
    )
    centre_of_mass_ratio: Number | None = field(
        None, unit="Lc/L", gt=0.0, lt=1.0, description="the same as a fraction of the length (Lc/L)"
    )
    interior: InteriorSpec | None = None
    counterweight: CounterweightSpec | None = None
    mass_properties: MassPropertiesSpec | None = None
    transverse_inertia_scale: Number = field(
        1.0, unit="", gt=0.0, le=100.0, description="factor on both transverse moments of inertia"
    )

    @model_validator(mode="after")
    def _shape(self) -> Self:
        if self.geometry is None:
            missing = [k for k in ("diameter", "length", "nose") if getattr(self, k) is None]
            if missing:
                raise ValueError(f"give {', '.join(missing)} (an analytic projectile), or geometry = {{ file = ... }}")
            if self.materials is not None:
                raise ValueError(
                    "materials name the solids of a geometry file: drop materials, or give"
                    " geometry = { file = ... } (an analytic projectile has body_density and a"
                    " counterweight)"
                )
            return self
        given = [
            k
            for k in (
                "diameter",
                "length",
                "nose",
                "body",
                "interior",
                "counterweight",
                "centre_of_mass",
                "centre_of_mass_ratio",
            )
            if getattr(self, k) is not None
        ]
        if given:
            raise ValueError(
                f"{', '.join(given)}: the geometry file sets the shape and its materials the mass;"
                " drop them (or drop geometry)"
            )
        if self.materials is not None and len(self.materials) > 50:
            raise ValueError(f"materials: {len(self.materials)} named; at most 50")
        if self.materials and self.mass is not None:
            raise ValueError("with materials the mass follows from the densities: drop mass (or materials)")
        return self

    @model_validator(mode="after")
    def _consistent(self) -> Self:
        wants_centre = self.centre_of_mass is not None or self.centre_of_mass_ratio is not None
        if self.centre_of_mass is not None and self.centre_of_mass_ratio is not None:
            raise ValueError("give centre_of_mass or centre_of_mass_ratio, not both")
        if self.counterweight is not None and self.interior is None:
            raise ValueError("counterweight needs an interior (a cavity to fill)")
        if self.mass_properties is not None:
            if self.mass is not None or wants_centre:
                raise ValueError(
                    "mass_properties sets mass and centre of mass itself:"
                    " drop mass, centre_of_mass and centre_of_mass_ratio"
                )
            return self
        if self._placed_by_mass:
            if self.mass is None or not wants_centre:
                raise ValueError(
                    "a counterweight without start and end needs mass and"
                    " centre_of_mass (or centre_of_mass_ratio) to place it"
                )
            return self
        if wants_centre:
            raise ValueError(
                "centre_of_mass places a counterweight that has no start and end;"
                " to set it directly give mass_properties"
            )
        if self.mass is not None and self.counterweight is not None:
            raise ValueError("with a placed counterweight the mass follows from the densities: drop mass")
        if self.mass is not None and self.body_density is not None:
            raise ValueError("give mass or body_density, not both")
        return self

    @model_validator(mode="after")
    def _buildable(self) -> Self:
        """The mesh room's own checks of the shape (nose shorter than the body, cavity inside the wall, ...),
        made here so that they fail before any meshing, naming the field."""
        if self.geometry is not None:
            return self  # measured when it is meshed (mesh.imported)
        span = None
        weight = self.counterweight
        if weight is not None and weight.start is not None and weight.end is not None:  # both or neither
            span = (weight.start, weight.end)
        ProjectileGeometry(self.profile(), self.interior.build() if self.interior else None, span)
        mass = self.mass_properties.mass if self.mass_properties is not None else self.mass
        assert self.diameter is not None and self.length is not None  # an analytic projectile has both (_shape)
        lightest = MIN_MEAN_DENSITY * 0.25 * math.pi * self.diameter**2 * self.length
        field_name = "mass_properties.mass" if self.mass_properties is not None else "mass"
        if mass is not None and mass < lightest:
            raise ValueError(
                f"{field_name} = {mass:g}: lighter than {MIN_MEAN_DENSITY:g} kg/m^3 over the bounding"
                f" cylinder (allowed: {field_name} >= {lightest:.3g} kg for this diameter and length)"
            )
        # the plausible range of a mass: no solid is denser than DENSITY.high (a mass in grams is 1000 times too
        # heavy); the cylinder's radius is the widest of the shank and a measured body (a flare)
        radius = max([self.diameter / 2, *(r for _, r in (self.body.points if self.body else []))])
        heaviest = DENSITY.high * math.pi * radius**2 * self.length
        if mass is not None and mass > heaviest:
            hint = slip_hint(mass, "kg", lightest, heaviest)
            raise ValueError(
                f"{field_name} = {number(mass)} kg: denser than {number(DENSITY.high)} kg/m^3, the densest solid, over"
                f" the bounding cylinder (allowed: {field_name} <= {heaviest:.3g} kg for this diameter and length)"
                + (f"; {hint}" if hint else "")
            )
        return self

    @property
    def _placed_by_mass(self) -> bool:
        """A counterweight without start and end, placed by the mass and centre of mass."""
        return self.counterweight is not None and self.counterweight.start is None and self.mass_properties is None

    @property
    def centre_target(self) -> float | None:
        """Target centre of mass from the tip (m), if any."""
        if self.centre_of_mass_ratio is not None:
            assert self.length is not None  # the ratio is of an analytic projectile (_shape)
            return self.centre_of_mass_ratio * self.length
        return self.centre_of_mass

    def profile(self) -> Profile:
        """The outer profile (mesh room)."""
        # an analytic projectile's (_shape)
        assert self.diameter is not None and self.length is not None and self.nose is not None
        return Profile(self.diameter, self.length, self.nose.build(), self.body.build() if self.body else None)

    def densities(self) -> dict[int, float]:
        """Density (kg/m^3) of each mesh region: the body and, with a counterweight, the counterweight
        (or a geometry file's named materials)."""
        body = {BODY: self.body_density or DEFAULT_BODY_DENSITY}
        if self.geometry is not None:
            return {**body, **{MATERIAL_BASE + k: d for k, d in enumerate((self.materials or {}).values())}}
        if self.interior is not None and self.counterweight is not None:
            return {**body, COUNTERWEIGHT: self.counterweight.density}
        return body

    def shape(self, placed: tuple[float, float] | None = None) -> ProjectileGeometry | FileGeometry:
        """The geometry to mesh: profile, cavity and the counterweight's span (placed here when the
        mass and centre of mass place it; with ``mass_properties`` an unplaced counterweight is
        left out, since the given properties replace the integrated ones).

        ``placed``: the span this spec's placement gave before (read back from a cache); used instead
        of placing the counterweight again, which takes about 0.6 s of root finding.
        A geometry file gives its :class:`~mesh.imported.FileGeometry`."""
        if self.geometry is not None:
            g = self.geometry
            assert g.sha256 is not None  # filled in when the file is read (GeometryFileSpec._readable)
            axis = (*g.axis,) if isinstance(g.axis, tuple) else g.axis
            return FileGeometry(
                str(g.file), g.sha256, g.unit, axis, tuple(self.materials or {}), g.cell_field, g.symmetry
            )
        profile = self.profile()
        if self.interior is None:
            return ProjectileGeometry(profile)
        interior = self.interior.build()
        weight = self.counterweight
        if weight is None or (weight.start is None and not self._placed_by_mass):
            return ProjectileGeometry(profile, interior)
        if weight.start is not None and weight.end is not None:  # both or neither (CounterweightSpec)
            span = (weight.start, weight.end)
        elif placed is not None:
            span = placed
        else:
            assert self.mass is not None and self.centre_target is not None  # placed by them (_consistent)
            span = place_counterweight(
                profile,
                interior,
                self.body_density or DEFAULT_BODY_DENSITY,
                weight.density,
                self.mass,
                self.centre_target,
            )
        return ProjectileGeometry(profile, interior, span)
