"""The target and the optional effects of a scene; each spec builds its ``fem_loads`` object."""

from __future__ import annotations

import functools
import math
from dataclasses import replace
from typing import Annotated, Any, Literal, Self

from pydantic import (
    Discriminator,
    SerializerFunctionWrapHandler,
    Tag,
    field_validator,
    model_serializer,
    model_validator,
)

from fem_loads.resistance import (
    LAW_FAMILIES,
    NAMED_LAWS,
    ResistanceLaw,
    concrete_cavity_expansion,
    concrete_strength_factor,
    locking_cavity_expansion,
    resistance_law,
)
from fem_loads.target import GAP, LEVEL, FreeSurface, Friction, FrontFace, LayeredTarget
from fem_loads.user_law import LawError, UserLaw, user_law

from . import plausible as ranges
from .base import Label, Number, Strict, field
from .plausible import implausible, number, slip_hint, upper_limit

__all__ = [
    "LawSpec",
    "PolynomialLawSpec",
    "PowerLawSpec",
    "MaterialLawSpec",
    "ConcreteLawSpec",
    "UserLawSpec",
    "LAW_TAGS",
    "LawChoice",
    "LayerSpec",
    "Target",
    "FrictionSpec",
    "FreeSurfaceSpec",
    "Effects",
    "build_law",
]


class DepthStrength(Strict):
    """Strength that grows with depth below the surface, on top of any built-in law's own."""

    depth_gradient: Number = field(
        0.0,
        unit="Pa/m",
        ge=0.0,
        le=1e10,
        plausible=ranges.STRENGTH_GRADIENT,
        description="k: the strength grows by k per metre below the surface",
    )
    strength_table: list[tuple[Number, Number]] | None = field(
        None,
        plausible=replace(ranges.STATIC_STRENGTH, column=1, column_name="extra strength", unit="Pa"),
        description="[depth (m), extra strength (Pa)] rows with increasing depths, linear between them",
        min_length=1,
        max_length=100,
    )

    @field_validator("strength_table")
    @classmethod
    def _increasing(cls, rows: list[tuple[float, float]] | None) -> list[tuple[float, float]] | None:
        if rows is None:
            return rows
        if any(not (0.0 <= depth <= 1e4 and 0.0 <= stress <= 1e11) for depth, stress in rows):
            raise ValueError("rows must be [depth, stress] with 0 <= depth <= 1e4 m and 0 <= stress <= 1e11 Pa")
        if any(b[0] <= a[0] for a, b in zip(rows, rows[1:])):
            raise ValueError("the depths must increase from row to row")
        return rows

    def _depth(self) -> dict[str, Any]:
        return {"k": self.depth_gradient, "strength_table": tuple(map(tuple, self.strength_table or ()))}


class LawSpec(DepthStrength):
    """A cavity-expansion law ``sigma_n = A sigma_0 + B rho_0 Vn^2`` by its coefficients."""

    model: Literal["cavity_expansion"] = "cavity_expansion"
    A: Number = field(ge=0.0, le=1e3, description="static coefficient")
    sigma_0: Number = field(unit="Pa", gt=0.0, le=1e11, plausible=ranges.STRENGTH, description="target strength")
    B: Number = field(ge=0.0, le=1e3, description="dynamic coefficient")
    rho_0: Number = field(unit="kg/m^3", gt=0.0, le=1e5, plausible=ranges.DENSITY, description="target density")

    def build(self) -> ResistanceLaw:
        return ResistanceLaw(self.A * self.sigma_0, self.B * self.rho_0, "cavity expansion", **self._depth())


class PolynomialLawSpec(DepthStrength):
    """A polynomial law ``sigma_n = c0 + c1 Vn + c2 Vn^2``."""

    model: Literal["polynomial"]
    c0: Number = field(
        unit="Pa", ge=0.0, le=1e11, plausible=ranges.STATIC_STRENGTH, description="strength at the surface"
    )
    # no plausible range for c1: a fitted viscous term may be negligibly small, and no unit slip is usual
    c1: Number = field(0.0, unit="Pa s/m", ge=0.0, le=1e10, description="coefficient of Vn")
    c2: Number = field(
        0.0, unit="kg/m^3", ge=0.0, le=1e6, plausible=ranges.DYNAMIC_DENSITY, description="coefficient of Vn^2"
    )

    def build(self) -> ResistanceLaw:
        return ResistanceLaw(self.c0, self.c2, "polynomial", c1=self.c1, **self._depth())


class PowerLawSpec(DepthStrength):
    """A power law ``sigma_n = c0 + c Vn^n``."""

    model: Literal["power"]
    c0: Number = field(
        unit="Pa", ge=0.0, le=1e11, plausible=ranges.STATIC_STRENGTH, description="strength at the surface"
    )
    # no plausible range for c: its unit, Pa (s/m)^n, and so its size, depend on the fitted n
    c: Number = field(unit="Pa (s/m)^n", ge=0.0, le=1e11, description="coefficient of Vn^n")
    n: Number = field(gt=0.0, le=10.0, description="exponent")

    def build(self) -> ResistanceLaw:
        return ResistanceLaw(self.c0, 0.0, "power", c=self.c, n=self.n, **self._depth())


class MaterialLawSpec(Strict):
    """A resistance law derived from material constants (docs/laws.md)."""

    model: Literal["locking_cavity_expansion"]
    sigma_0: Number = field(unit="Pa", gt=0.0, le=1e11, plausible=ranges.STRENGTH, description="target strength")
    rho_0: Number = field(unit="kg/m^3", gt=0.0, le=1e5, plausible=ranges.DENSITY, description="target density")
    locking_strain: Number = field(gt=0.0, lt=1.0, description="volumetric strain eta* at locking")

    def build(self) -> ResistanceLaw:
        return locking_cavity_expansion(self.sigma_0, self.rho_0, self.locking_strain)


class ConcreteLawSpec(Strict):
    """Concrete by its compressive strength and density: Forrestal's cavity expansion ``S f'c + rho Vn^2`` with
    Frew et al.'s ``S = 82.6 (f'c / MPa)^-0.544`` (docs/laws.md)."""

    model: Literal["concrete"]
    compressive_strength: Number = field(
        unit="Pa",
        gt=0.0,
        le=1e9,
        plausible=ranges.CONCRETE_STRENGTH,
        description="f'c: the unconfined compressive strength",
    )
    density: Number = field(
        unit="kg/m^3", gt=0.0, le=1e5, plausible=ranges.DENSITY, description="rho: the concrete's density"
    )
    S: Number | None = field(
        None,
        ge=0.0,
        le=1e3,
        description="the static coefficient; filled in from f'c by Frew et al.'s fit when not given",
    )

    def _fill_in(self) -> None:
        """``S`` from f'c by Frew et al.'s fit, held to the limit its field states: a tiny f'c (35 for 35 MPa)
        gives an ``S`` of thousands, refused naming f'c and the value it probably meant."""
        if self.S is not None:
            return
        factor = concrete_strength_factor(self.compressive_strength)
        limit = upper_limit(type(self).model_fields["S"])
        if factor > limit:
            strength = self.compressive_strength
            hint = slip_hint(strength, "Pa", ranges.CONCRETE_STRENGTH.low, ranges.CONCRETE_STRENGTH.high)
            raise implausible(
                "S",
                f"{number(factor, 3)} filled in from compressive_strength = {number(strength)} Pa by Frew et al.'s fit",
                f"allowed S <= {number(limit)}; is compressive_strength in Pa?" + (f" {hint}" if hint else ""),
            )
        self.S = factor

    def data_range_warnings(self, where: str) -> list[str]:
        """A filled-in ``S`` for an f'c outside the concrete Frew et al. fitted it to is an extrapolation: one line
        naming the source and its range (``where``: the law's dotted path)."""
        strength, factor, (low, high) = self.compressive_strength, self.S, (ranges.FREW_FIT.low, ranges.FREW_FIT.high)
        if factor is None or low <= strength <= high:
            return []
        if not math.isclose(factor, concrete_strength_factor(strength), rel_tol=1e-12):
            return []  # S given: the fit is not used
        return [
            f"{where}.compressive_strength = {number(strength / 1e6)} MPa lies outside the {number(low / 1e6)}-"
            f"{number(high / 1e6)} MPa of the concrete and grout that Frew et al. fitted S to (Int. J. Impact Eng."
            f" 21, 1998): S = {number(factor, 3)} is an extrapolation; give {where}.S, or fit it (docs/laws.md)"
        ]

    def build(self) -> ResistanceLaw:
        return concrete_cavity_expansion(self.compressive_strength, self.density, self.S)


class UserLawSpec(Strict):
    """A law of the user's own: ``def name(normal_velocity, depth, p1, ...)`` in a Python file (docs/laws.md)."""

    function: Label = field(description="'path/to/file.py:name', the path relative to the scene file's folder")
    parameters: dict[str, Number] = field({}, description="the function's arguments after the first two, by name")
    sha256: Label | None = field(
        None,
        description="the file's digest: filled in when the scene is read; a changed"
        " file is refused by a resolved scene that holds the old one",
    )

    @model_validator(mode="after")
    def _usable(self) -> Self:
        law = self.build()
        if self.sha256 is not None and self.sha256 != law.sha256:
            raise ValueError(
                f"function = {self.function!r}: the file changed since this scene was resolved (sha256"
                f" {law.sha256[:12]}..., the scene holds {self.sha256[:12]}...); drop sha256 to use it as it is now"
            )
        self.sha256 = law.sha256
        return self

    def build(self) -> UserLaw:
        """The checked law (:func:`fem_loads.user_law.user_law`; read, probed and compiled once per process)."""
        try:
            return _user_law(self.function, tuple(sorted(self.parameters.items())))
        except LawError as exc:
            raise ValueError(str(exc)) from None


@functools.lru_cache(maxsize=64)
def _user_law(function: str, parameters: tuple[tuple[str, float], ...]) -> UserLaw:
    return user_law(function, dict(parameters))


#: the tag of each table form of a law (besides a name), with its spec
LAW_TAGS: dict[str, type[Strict]] = {
    "coefficients": LawSpec,
    "polynomial": PolynomialLawSpec,
    "power": PowerLawSpec,
    "material": MaterialLawSpec,
    "concrete": ConcreteLawSpec,
    "user": UserLawSpec,
}
_MODEL_TAGS = {"cavity_expansion": "coefficients", "locking_cavity_expansion": "material", "concrete": "concrete"}


def _law_kind(value: object) -> str:
    if isinstance(value, str):
        return "name"
    if isinstance(value, Strict):
        return next(tag for tag, spec in LAW_TAGS.items() if isinstance(value, spec))
    if isinstance(value, dict):
        if "function" in value:
            return "user"
        model = value.get("model")
        if isinstance(model, str) and (model in LAW_FAMILIES or model in _MODEL_TAGS):
            return _MODEL_TAGS.get(model, model)
    return "coefficients"


LawChoice = Annotated[
    Annotated[str, Tag("name")]
    | Annotated[LawSpec, Tag("coefficients")]
    | Annotated[PolynomialLawSpec, Tag("polynomial")]
    | Annotated[PowerLawSpec, Tag("power")]
    | Annotated[MaterialLawSpec, Tag("material")]
    | Annotated[ConcreteLawSpec, Tag("concrete")]
    | Annotated[UserLawSpec, Tag("user")],
    Discriminator(_law_kind),
]
AnyLawSpec = LawSpec | PolynomialLawSpec | PowerLawSpec | MaterialLawSpec | ConcreteLawSpec | UserLawSpec


def build_law(law: str | AnyLawSpec) -> ResistanceLaw | UserLaw:
    """The resistance law a scene names, gives by a family's coefficients, derives from material constants or
    reads from the user's file."""
    return resistance_law(law) if isinstance(law, str) else law.build()


def _check_law_name(value: object) -> object:
    if isinstance(value, str) and value not in NAMED_LAWS:
        raise ValueError(
            f"unknown law {value!r}: must be one of {', '.join(sorted(NAMED_LAWS))}, a table of a family's"
            f" coefficients (model = {', '.join(dict.fromkeys([*LAW_FAMILIES, *_MODEL_TAGS]))})"
            " or function = 'file.py:name'"
        )
    return value


#: the law name of a gap between layers: empty space, no stress
AIR = "air"


class LayerSpec(Strict):
    """One layer of a layered target, or a gap (``law = "air"``); the last layer without a thickness goes on
    forever, with one the target ends at its rear face."""

    thickness: Number | None = field(None, unit="m", gt=0.0, le=1e4, plausible=ranges.LAYER)
    law: LawChoice = field(description='a named law, a table of its coefficients, or "air" for a gap')

    _known_name = field_validator("law")(
        classmethod(lambda cls, value: value if value == AIR else _check_law_name(value))
    )


class Target(Strict):
    """The target below its front face, the plane ``Z = 0`` turned about ``Y`` by ``inclination``: homogeneous
    (``law``) or layered (``layers``), a half-space or, when the last layer has a thickness, a slab."""

    law: LawChoice = field("soil", description="a named law or a table of its coefficients")
    layers: list[LayerSpec] | None = field(None, description="layers from the front face in")
    inclination: Number = field(
        0.0,
        unit="deg",
        gt=-90.0,
        lt=90.0,
        description="turn of the front face and every interface about the Y axis: the face's normal leans from +Z"
        " towards +X, so a vertical shot meets it as a level target meets oblique_angle = inclination",
    )

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
        gaps = [layer.law == AIR for layer in self.layers]
        if gaps[0] or gaps[-1]:
            raise ValueError(
                'layers: a gap (law = "air") lies between two layers (allowed: not the first layer, where the'
                " target starts at its first material, nor the last, where it ends)"
            )
        return self

    @model_serializer(mode="wrap")
    def _without_unused_law(self, handler: SerializerFunctionWrapHandler) -> dict[str, Any]:
        # a layered target's law is unused: left out, the dump reads back as the same target
        data = handler(self)
        if self.layers is not None:
            data.pop("law", None)
        return data

    @property
    def face(self) -> FrontFace:
        """The front face, through the origin, its normal turned from +Z towards +X by the inclination."""
        if self.inclination == 0.0:
            return LEVEL
        angle = math.radians(self.inclination)
        return FrontFace((math.sin(angle), 0.0, math.cos(angle)), 0.0)

    @property
    def inner_faces(self) -> tuple[float, ...]:
        """The depths (m below the front face) of the faces inside the target: its layers' interfaces and its rear
        face, if it has one."""
        depths, top = [], 0.0
        for layer in self.layers or []:
            if layer.thickness is not None:
                top += layer.thickness
                depths.append(top)
        return tuple(depths)

    @property
    def thickness(self) -> float:
        """The depth (m) of the rear face below the front face: ``inf`` for a half-space."""
        layers = self.layers or []
        return math.inf if not layers or layers[-1].thickness is None else self.inner_faces[-1]

    def warnings(self, speed: float) -> list[str]:
        """Plain-language doubts about the target's laws for a shot at ``speed`` (m/s), one line each (empty when
        none): an empirical law used outside the data it was fitted to, or concrete struck faster than a steel nose
        stays whole (:func:`~.plausible.mass_loss_warnings`; :attr:`~.schema.Scene.warnings`)."""
        if self.layers is None:
            laws = [("target.law", self.law)]
        else:
            laws = [(f"target.layers.{index}.law", layer.law) for index, layer in enumerate(self.layers)]
        concrete = [(where, law) for where, law in laws if isinstance(law, ConcreteLawSpec)]
        lines = [line for where, law in concrete for line in law.data_range_warnings(where)]
        return lines + ranges.mass_loss_warnings(speed, [where for where, _ in concrete], self.layers is not None)

    def build_rear_face(self) -> FrontFace | None:
        """The plane past which the whole body has perforated the target, facing out of its rear (a point's height
        above it is its depth below the rear face); None for a half-space."""
        return None if math.isinf(self.thickness) else self.face.behind(self.thickness)

    def build(self) -> ResistanceLaw | UserLaw | LayeredTarget:
        """The law of a homogeneous target, or the layers (a gap's law, and behind a slab's rear face,
        :data:`~fem_loads.target.GAP`)."""
        if self.layers is None:
            return build_law(self.law)
        laws = tuple(GAP if layer.law == AIR else build_law(layer.law) for layer in self.layers)
        thicknesses = tuple(layer.thickness for layer in self.layers if layer.thickness is not None)
        return LayeredTarget(thicknesses, laws + ((GAP,) if len(thicknesses) == len(laws) else ()))


class FrictionSpec(Strict):
    """Tangential stress opposite to the local slip."""

    model: Literal["none", "coulomb", "capped"] = field(
        "none", description="coulomb: tau = mu sigma_n; capped: tau = min(mu sigma_n, tau_s)"
    )
    coefficient: Number = field(0.1, ge=0.0, le=5.0, description="mu")
    cap: Number | None = field(
        None, unit="Pa", gt=0.0, le=1e11, plausible=ranges.SHEAR_STRENGTH, description="tau_s of the capped model"
    )

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
    """Free-surface reduction of the normal stress, a smooth ramp over its depth (docs/effects.md)."""

    depth: Number = field(
        unit="m",
        gt=0.0,
        le=1e3,
        plausible=ranges.FREE_SURFACE_DEPTH,
        description="full resistance from this distance into the target",
    )
    surface_fraction: Number = field(0.0, ge=0.0, le=1.0, description="fraction of it at the face")
    faces: list[Literal["front", "rear"]] = field(
        ["front"],
        min_length=1,
        max_length=2,
        description='the free faces it applies near: "front", and "rear" for the rear face of a target with one'
        " (the faces of gaps are not reduced; docs/targets.md)",
    )

    def build(self, rear_face: float = math.inf) -> FreeSurface:
        """The reduction, ``rear_face`` (m below the front face) the target's rear face (``inf``: none)."""
        return FreeSurface(
            self.depth, self.surface_fraction, "front" in self.faces, rear_face if "rear" in self.faces else math.inf
        )


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
    contact: Literal["one_sided", "centred"] = field(
        "one_sided",
        description="where the contact ramp lies: from Vn = 0 up (one_sided: an element sliding along the"
        " target is unloaded) or centred on Vn = 0 (half loaded there); two models with two limits"
        " (docs/model.md)",
    )
    free_surface: FreeSurfaceSpec | None = None
    exposure: bool = field(
        True,
        description="only surface the target can reach carries stress: a point whose ray along the body's"
        " velocity meets the body is unloaded (base recesses, grooves, the lee of fins); false loads every point"
        " with Vn > 0 (docs/geometry.md)",
    )
    gravity: bool = field(False, description="the projectile's weight acts during the run")
    gravity_acceleration: Number = field(9.80665, unit="m/s^2", ge=0.0, le=1e3, description="g, downward (-Z)")

    @property
    def contact_ramp(self) -> dict[str, Any]:
        """``contact_width``, ``contact_incidence`` and ``contact``, as the load and the 1-D reference take them."""
        widths = {"contact_width": self.contact_width, "contact_incidence": self.contact_incidence}
        return {**widths, "contact": self.contact}

    @property
    def sharp_contact(self) -> bool:
        """Whether the contact factor is the sharp switch at ``Vn = 0`` (both widths zero)."""
        return self.contact_width == 0.0 and self.contact_incidence == 0.0
