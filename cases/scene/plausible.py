"""What a physical input of a scene plausibly is: one range per kind of input, beyond the hard range of its field.

A value inside a field's hard range (``gt``, ``le``, ...) can still describe nothing real: ``compressive_strength =
35`` is 35 Pa, a millionth of any concrete's strength, and most likely 35 MPa written without its ``e6``.  Each
field that describes a physical quantity names one of the ranges below (``field(..., plausible=DENSITY)``,
:mod:`.base`); one validator (:func:`check_plausible`, run by every model after its fields) refuses a value
outside it in one line that names the field, its unit, the plausible range and, when the value times a usual
slip of unit (MPa for Pa, mm for m, g/cm^3 for kg/m^3) lands inside the range, the value it probably meant
(:func:`slip_hint`, which the hard-range messages and the checks that tie fields together use too).

The ranges are generous: they must never refuse a real target or projectile, only a unit slip.  Inputs whose
plausible values fill their hard range (speeds, angles, dimensionless coefficients, a rate term whose unit
depends on a fitted exponent) name no range; a mass is held to its body's size instead (a mean density from
100 to :data:`DENSITY`'s highest, ``Projectile``).  The last entry is of another kind: the data an empirical
law was fitted to, outside which the scene runs but warns (:data:`FREW_FIT`).
"""

from __future__ import annotations

import math
from collections.abc import Iterator
from dataclasses import asdict, dataclass
from typing import Any

from pydantic import BaseModel
from pydantic_core import PydanticCustomError

__all__ = [
    "Plausible",
    "SLIPS",
    "STATIC_STRENGTH",
    "STRENGTH",
    "CONCRETE_STRENGTH",
    "SHEAR_STRENGTH",
    "STRENGTH_GRADIENT",
    "DENSITY",
    "DYNAMIC_DENSITY",
    "DIAMETER",
    "BODY_LENGTH",
    "POSITION",
    "WALL",
    "MESH_SIZE",
    "LAYER",
    "FREE_SURFACE_DEPTH",
    "FREW_FIT",
    "RIGID_IN_CONCRETE",
    "mass_loss_warnings",
    "plausible_of",
    "check_plausible",
    "implausible",
    "slip_hint",
    "number",
    "upper_limit",
]


@dataclass(frozen=True)
class Plausible:
    """The values a physical input plausibly takes: ``low <= value <= high`` in the field's own unit (and ``0``
    too when ``zero``: a term left out).  ``what`` names the quantity in the message (``"concrete's compressive
    strength"``), ``shown_in`` the unit the message also gives the range in when it differs from the field's
    (``"MPa"`` for a field in Pa).  ``column``: in a field of rows (a strength table), the column it applies to,
    ``column_name`` that column's name and ``unit`` its unit (a field of rows records none)."""

    low: float
    high: float
    what: str
    shown_in: str = ""
    zero: bool = False
    column: int | None = None
    column_name: str = ""
    unit: str = ""

    def holds(self, value: float) -> bool:
        return (self.zero and value == 0.0) or self.low <= value <= self.high

    def allowed(self, unit: str) -> str:
        """``1e6 to 5e8 Pa, about 1-500 MPa``: the range in the field's unit, and in ``shown_in``."""
        text = f"{'0, or ' if self.zero else ''}{number(self.low)} to {number(self.high)} {unit}".rstrip()
        factor = UNITS.get(unit, {}).get(self.shown_in)
        if factor is not None and self.shown_in != unit:
            text += f", about {number(self.low / factor)}-{number(self.high / factor)} {self.shown_in}"
        return text


#: the usual slips of each unit, most likely first: a value meant in the slipped unit, times the factor, is in SI
SLIPS: dict[str, tuple[tuple[str, float], ...]] = {
    "Pa": (("MPa", 1e6), ("kPa", 1e3), ("GPa", 1e9)),
    "Pa/m": (("MPa/m", 1e6), ("kPa/m", 1e3)),
    "kg/m^3": (("g/cm^3", 1e3),),
    "m": (("mm", 1e-3), ("cm", 1e-2)),
    "kg": (("g", 1e-3),),
}
#: the units a range is also shown in, as factors to SI (the slips, and each unit to itself)
UNITS: dict[str, dict[str, float]] = {unit: {unit: 1.0, **dict(slips)} for unit, slips in SLIPS.items()}

# ---------------------------------------------------------------------------------------------------------------
# The table: one range per kind of input, and where it comes from.  Fields name these (field(..., plausible=...)).

#: the static term of a law, Pa (c0, a strength table's extra strength): from a very soft clay or snow (about
#: 10 kPa; soils are about 0.1-100 MPa: the named soil laws' A sigma_0 are 13.5-20.3 MPa) through concrete
#: (S f'c: 0.5 GPa at 51 MPa) and rock to armour steel (the static term of cavity expansion in metals is about
#: 4-6 times the yield stress: 1-6 GPa); 10 GPa is above any of them.  0: no static term.
STATIC_STRENGTH = Plausible(1e4, 1e10, "a target's static strength", "MPa", zero=True)
#: a target's strength sigma_0 (Pa), with A the static term: the same materials (soil 10 MPa, grout 51 MPa)
STRENGTH = Plausible(1e4, 1e10, "a target's strength", "MPa")
#: concrete's unconfined compressive strength f'c, Pa: from the lightest foamed concretes (a few tenths of a MPa)
#: and lean or early-age mixes (a few MPa) through normal (20-60 MPa) and high-strength concrete to
#: ultra-high-performance concrete (150-250 MPa; 500 MPa leaves room above it): "about 10-200 MPa" for
#: structural concrete, widened both ways.  At 0.1 MPa Frew et al.'s S is 289, inside its limit of 1000.
CONCRETE_STRENGTH = Plausible(1e5, 5e8, "concrete's compressive strength", "MPa")
#: the cap tau_s of capped friction, Pa: a soil's shear strength (about 1 kPa for a soft mud) to a metal's (about
#: 1 GPa); the shipped studies use 10 MPa
SHEAR_STRENGTH = Plausible(1e3, 1e10, "a shear strength", "MPa")
#: strength growth with depth, Pa/m: a soil's overburden grows by about rho g = 2e4 Pa/m, times a factor of
#: order 1-100 for its strength (the studies use 2-3 MPa/m); from 100 Pa/m to 1 GPa/m.  0: none.
STRENGTH_GRADIENT = Plausible(1e2, 1e9, "a strength's growth with depth", "MPa/m", zero=True)
#: a solid's density, kg/m^3, of a target or a projectile's part: from polymer foams (about 20-30) through soils,
#: concrete, steel (7850) and tungsten alloys (about 18 000) to osmium (22 590), the densest element
DENSITY = Plausible(20.0, 25e3, "a solid's density", "g/cm^3")
#: the coefficient of Vn^2 (c2 = B rho_0, kg/m^3): B of about 0.5-4 times a solid's density.  0: no such term.
DYNAMIC_DENSITY = Plausible(10.0, 1e5, "a law's B rho_0", "g/cm^3", zero=True)
#: a projectile's diameter, m: from a 1 mm pellet or fragment through small-arms cores (about 5 mm) and shells
#: (0.155 m) to the largest penetrating bombs (about 0.8 m)
DIAMETER = Plausible(1e-3, 2.5, "a projectile's diameter", "mm")
#: a projectile's length, m: a few mm (a pellet) to the longest penetrating bombs (about 6 m)
BODY_LENGTH = Plausible(1e-3, 20.0, "a projectile's length", "mm")
#: a position along the projectile, m from its tip (centre of mass, a counterweight's ends): within a length
POSITION = Plausible(1e-3, 20.0, "a position along a projectile", "mm")
#: a wall, plate or flat of the projectile, m: 0.1 mm to the largest diameter
WALL = Plausible(1e-4, 2.5, "a projectile's wall, plate or flat", "mm")
#: a layer of the target, m: a 0.1 mm sheet to 1 km (a thicker layer is a half-space: give it no thickness)
LAYER = Plausible(1e-4, 1e3, "a target layer's thickness", "m")
#: a mesh size, m: 10 um to 1 m (the scene holds it to the projectile too: at most its diameter)
MESH_SIZE = Plausible(1e-5, 1.0, "a mesh size", "mm")
#: the depth of the free-surface reduction, m: 0.1 mm to 100 m (a crater is one or two diameters deep)
FREE_SURFACE_DEPTH = Plausible(1e-4, 100.0, "a free-surface depth", "m")

# ---------------------------------------------------------------------------------------------------------------
# The data an empirical law was fitted to: outside it the law runs, and the scene warns (Scene.warnings).

#: the unconfined compressive strengths of the concrete and grout Frew et al. fitted S = 82.6 (f'c/MPa)^-0.544 to:
#: "about 13 to 60 MPa", as docs/laws.md states it (from secondary sources; not checked against the paper itself)
FREW_FIT = Plausible(13e6, 60e6, "the concrete and grout of Frew et al.'s fit of S", "MPa")
#: the impact speeds, m/s, at which a steel nose stays whole in concrete: to about 1 km/s.  Forrestal et al.'s 1996
#: shots into 51 MPa grout (cases/series/forrestal1996_concrete.csv) are predicted within 6 % up to 1069 m/s and
#: 19.6 % too deep at 1201 m/s, where the measured depths flatten as the nose loses mass (docs/laws.md)
RIGID_IN_CONCRETE = Plausible(0.0, 1000.0, "the impact speeds at which a steel nose stays whole in concrete", "m/s")


def number(value: float, digits: int = 6) -> str:
    """A number as a scene file would write it, to ``digits`` significant digits: ``35``, ``0.0305``, ``2300``,
    ``1e6``, ``2.5e8`` (``21900`` for 21928 to 3 digits)."""
    if value == 0.0 or not math.isfinite(value):
        return f"{value:g}"
    value = float(f"{value:.{digits}g}")
    if 1e-4 <= abs(value) < 1e5:
        return f"{value:.6g}"
    mantissa, _, exponent = f"{value:.4g}".partition("e")
    if not exponent:
        mantissa, _, exponent = f"{value:.4e}".partition("e")
        mantissa = mantissa.rstrip("0").rstrip(".")
    return f"{mantissa}e{int(exponent)}"


def _meant(value: float) -> str:
    """A suggested value in engineering form: ``35e6`` (35 MPa in Pa), ``0.155``, ``2300``."""
    if 1e-4 <= abs(value) < 1e5:
        return f"{value:.6g}"
    exponent = 3 * math.floor(math.log10(abs(value)) / 3)
    return f"{value / 10.0**exponent:.6g}e{exponent}"


def slip_hint(value: float, unit: str, low: float, high: float) -> str:
    """``"did you mean 35e6 (35 MPa)?"``: the first usual slip of ``unit`` that puts ``value`` in ``[low, high]``,
    or ``""``."""
    for slipped, factor in SLIPS.get(unit, ()):
        if low <= value * factor <= high:
            return f"did you mean {_meant(value * factor)} ({number(value)} {slipped})?"
    return ""


def implausible(field: str, shown: str, text: str) -> PydanticCustomError:
    """The error of a value outside its plausible range, or of a filled-in value outside its limits: the scene's
    explanation prints it as ``{path}.{field} = {shown}: {text}``."""
    return PydanticCustomError(
        "implausible", "{field} = {shown}: {text}", {"field": field, "shown": shown, "text": text}
    )


def plausible_of(info: Any) -> Plausible | None:
    """The plausible range a field records (``json_schema_extra["plausible"]``), or None."""
    extra = getattr(info, "json_schema_extra", None)
    found = extra.get("plausible") if isinstance(extra, dict) else None
    return Plausible(**found) if isinstance(found, dict) else None


def as_extra(plausible: Plausible) -> dict[str, Any]:
    """The range as a field records it: plain JSON, so that the schema stays printable."""
    return asdict(plausible)


def upper_limit(info: Any) -> float:
    """The upper bound a field states (``le`` or ``lt``), ``inf`` without one."""
    bounds = [
        getattr(item, name) for item in getattr(info, "metadata", []) for name in ("le", "lt") if hasattr(item, name)
    ]
    return min(map(float, bounds), default=math.inf)


def _quoted(key: str) -> str:
    return key if key.isidentifier() else repr(key)


def _values(name: str, value: Any, plausible: Plausible) -> Iterator[tuple[str, Any, float]]:
    """``(dotted name, shown value, number)`` for each number of a field's value that the range applies to."""
    if isinstance(value, dict):  # densities by name
        for key, item in value.items():
            yield f"{name}.{_quoted(str(key))}", item, item
    elif isinstance(value, (list, tuple)) and plausible.column is not None:  # rows of a table
        for index, row in enumerate(value):
            yield f"{name}.{index}", row, row[plausible.column]
    elif isinstance(value, (int, float)) and not isinstance(value, bool):
        yield name, value, value


def check_plausible(model: BaseModel) -> None:
    """Refuse the first value of ``model``'s fields outside its field's plausible range, in one line (an
    ``implausible`` error, which the scene's explanation prints with the field's dotted path)."""
    for name, info in type(model).model_fields.items():
        plausible = plausible_of(info)
        value = getattr(model, name)
        if plausible is None or value is None:
            continue
        extra = info.json_schema_extra
        unit = plausible.unit or (str(extra.get("unit", "")) if isinstance(extra, dict) else "")
        for where, shown, item in _values(name, value, plausible):
            if plausible.holds(item):
                continue
            side = "low" if item < plausible.low else "high"
            if plausible.column is not None:
                row = "[" + ", ".join(number(v) for v in shown) + "]"
                text = f"its {plausible.column_name} {number(item)} {unit} is too {side} for {plausible.what}"
                raise implausible(
                    where, row, f"{text} (allowed: {plausible.allowed(unit)})" + _hint(item, unit, plausible)
                )
            text = f"too {side} for {plausible.what} (allowed: {plausible.allowed(unit)})"
            raise implausible(where, f"{number(item)} {unit}".rstrip(), text + _hint(item, unit, plausible))


def _hint(value: float, unit: str, plausible: Plausible) -> str:
    hint = slip_hint(value, unit, plausible.low, plausible.high)
    return f"; {hint}" if hint else ""


def mass_loss_warnings(speed: float, concrete: list[str], layered: bool) -> list[str]:
    """One line when a shot at ``speed`` (m/s) strikes concrete (``concrete``: its laws' dotted paths; ``layered``:
    the target has layers) above :data:`RIGID_IN_CONCRETE`: the nose loses mass there, which the rigid model does not
    follow, so it overstates the depth; on one law, the empirical formulas are the comparison to make."""
    onset = RIGID_IN_CONCRETE.high
    if not concrete or speed <= onset:
        return []
    return [
        f"impact.speed = {number(speed)} m/s into concrete ({concrete[0]}): above about {number(onset)} m/s a"
        " steel nose loses mass, which the rigid model does not follow, so the depth may be overstated"
        " (Forrestal et al.'s 1996 shots: within 6 % up to 1069 m/s, 19.6 % too deep at 1201 m/s)"
        + ("" if layered else "; compare the empirical formulas: penetrate formulas SCENE")
        + " (docs/laws.md)"
    ]
