"""``penetrate formulas``: the field's empirical equations for a scene, beside what its DAFL run gives.

A scene's projectile (mass, diameter, nose), impact speed and concrete target (compressive strength, density,
a slab's thickness) are the inputs of every formula of :mod:`cases.reference.empirical`.  Each estimate carries
its checks: the scene's quantities against the range of the formula's data, each range marked by whether it was
read in the formula's source or taken from a compilation not checked against it.  A target the formulas do not
describe (a law that is not the concrete family, layers) is refused in one line.
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from mesh.profile import BluntOgiveNose, ConeNose, OgiveNose, SecantOgiveNose

from ...reference import empirical as eq
from ...run import prepare_projectile
from ...scene import InputError, Scene
from ..engine.report import Report, markdown_table, number_cell

if TYPE_CHECKING:
    from .series import Series

__all__ = ["FormulaInputs", "Formulas", "formula_inputs", "formulas", "formulas_report", "formula_rows", "NDRC_NOSES"]

NDRC_NOSES = tuple(eq.NDRC_NOSE_FACTORS)


@dataclass(frozen=True)
class FormulaInputs:
    """What the formulas take from a scene (SI): ``nose_factor`` is the cavity-expansion ``N*`` of its nose,
    ``ndrc_nose`` the NDRC's kind of nose, ``young_nose`` Young's, ``thickness`` the slab's (``inf``: none)."""

    mass: float
    diameter: float
    speed: float
    strength: float
    density: float
    nose_factor: float
    nose_length: float
    ndrc_nose: str
    young_nose: str
    thickness: float
    oblique_angle: float
    attack_angle: float


@dataclass
class Formulas:
    """What :func:`formulas` returns: the inputs, an estimate per formula and the messages on them."""

    inputs: FormulaInputs
    estimates: list[eq.Estimate]
    messages: list[str] = field(default_factory=list)

    def as_dict(self) -> dict:
        from dataclasses import asdict

        return {
            "inputs": asdict(self.inputs),
            "formulas": [e.as_dict() for e in self.estimates],
            "messages": list(self.messages),
        }


def formula_inputs(scene: Scene, ndrc_nose: str | None = None) -> FormulaInputs:
    """The formulas' inputs from ``scene``; one line naming the field when the scene is not one they describe."""
    from ...scene.target import ConcreteLawSpec

    if scene.target.layers is not None:
        raise InputError("target.layers: the empirical formulas take one concrete target; give target.law instead")
    law = scene.target.law
    if not isinstance(law, ConcreteLawSpec):
        shown = law if isinstance(law, str) else getattr(law, "model", type(law).__name__)
        raise InputError(
            f"target.law = {shown}: the empirical formulas describe concrete; give"
            ' target.law = { model = "concrete", compressive_strength = ..., density = ... }'
        )
    if scene.projectile.geometry is not None:
        raise InputError("projectile.geometry: the empirical formulas need an analytic projectile (diameter, nose)")
    prepared = prepare_projectile(scene)
    profile = prepared.profile
    nose = profile.nose
    if isinstance(nose, BluntOgiveNose):
        kinds = ("blunt", "ogive")
    elif isinstance(nose, OgiveNose) and nose.crh <= 0.5:
        kinds = ("spherical", "ogive")
    elif isinstance(nose, (OgiveNose, SecantOgiveNose)):
        kinds = ("very_sharp", "ogive")
    elif isinstance(nose, ConeNose):
        kinds = ("very_sharp", "cone")
    else:
        if ndrc_nose is None:
            raise InputError(
                f"projectile.nose: a measured nose has no NDRC nose kind; give --ndrc-nose ({', '.join(NDRC_NOSES)})"
            )
        kinds = (ndrc_nose, "ogive")
    return FormulaInputs(
        mass=float(prepared.mass.mass),
        diameter=float(2.0 * profile.radius),
        speed=float(scene.impact.speed),
        strength=float(law.compressive_strength),
        density=float(law.density),
        nose_factor=float(profile.nose_factor()),
        nose_length=float(profile.nose_length),
        ndrc_nose=ndrc_nose or kinds[0],
        young_nose=kinds[1],
        thickness=float(scene.target.thickness),
        oblique_angle=float(scene.impact.oblique_angle),
        attack_angle=float(scene.impact.attack_angle),
    )


def _normal(inputs: FormulaInputs) -> list[eq.Check]:
    """Every formula is for a normal impact: the scene's obliquity and attack angle, allowed 0 only."""
    return [
        eq.Check("oblique angle", inputs.oblique_angle, 0.0, 0.0, "deg", True),
        eq.Check("attack angle", inputs.attack_angle, 0.0, 0.0, "deg", True),
    ]


def formulas(scene: Scene, ndrc_nose: str | None = None, reinforcement: float = 0.0) -> Formulas:
    """Every formula of :mod:`cases.reference.empirical` for ``scene``: ``ndrc_nose`` overrides the NDRC's nose
    kind chosen from the scene's nose, ``reinforcement`` is the volume percentage of steel in Young's S-number."""
    i = formula_inputs(scene, ndrc_nose)
    m, d, v, fc, rho = i.mass, i.diameter, i.speed, i.strength, i.density
    n_ndrc = eq.NDRC_NOSE_FACTORS[i.ndrc_nose]
    thick = i.thickness / d if math.isfinite(i.thickness) else 6.0
    estimates = []

    x_ndrc = eq.ndrc_depth(m, d, v, fc, n_ndrc)
    ndrc = eq.Estimate("modified NDRC", x_ndrc, eq.SOURCES["modified NDRC"], _normal(i))
    ndrc.scabbing = eq.scabbing_thickness(x_ndrc, d)
    ndrc.perforation = eq.perforation_thickness(x_ndrc, d)
    ndrc.checks += [
        eq.Check("x/d (scabbing)", x_ndrc / d, 0.0, 11.75, "", True),
        eq.Check("x/d (perforation)", x_ndrc / d, 0.0, 13.5, "", False),
    ]
    estimates.append(ndrc)

    degen = eq.Estimate(
        "Degen (perforation, on the NDRC's depth)",
        None,
        eq.SOURCES["Degen perforation"],
        _normal(i) + [eq.Check("tp/d", eq.degen_perforation_thickness(x_ndrc, d) / d, 0.0, 18.0, "", True)],
    )
    degen.perforation = eq.degen_perforation_thickness(x_ndrc, d)
    estimates.append(degen)

    x_ace = eq.ace_depth(m, d, v, fc)
    ace = eq.Estimate("ACE", x_ace, eq.SOURCES["ACE"], _normal(i))
    ace.scabbing = eq.scabbing_thickness(x_ace, d)
    ace.perforation = eq.perforation_thickness(x_ace, d)
    ace.checks.append(eq.Check("x/d (perforation)", x_ace / d, 0.0, 13.5, "", True))
    estimates.append(ace)

    ukaea = eq.Estimate("UKAEA", eq.ukaea_depth(m, d, v, fc, n_ndrc), eq.SOURCES["UKAEA"], _normal(i))
    ukaea.checks += [
        eq.Check("impact speed", v, 25.0, 300.0, "m/s", False),
        eq.Check("compressive strength", fc / 1e6, 22.0, 44.0, "MPa", False),
        eq.Check("M/d^3", m / d**3, 5e3, 2e5, "kg/m^3", False),
    ]
    estimates.append(ukaea)

    li_chen = eq.Estimate(
        "Li and Chen",
        eq.li_chen_depth(m, d, v, fc, rho, i.nose_factor, i.nose_length),
        eq.SOURCES["Li and Chen"],
        _normal(i),
    )
    estimates.append(li_chen)

    s_number = eq.young_concrete_s_number(fc, reinforcement, 1.0, thick)
    n_young = eq.young_nose_coefficient(i.young_nose, i.nose_length, d)
    young = eq.Estimate("Young", eq.young_depth(m, d, v, s_number, n_young), eq.SOURCES["Young"], _normal(i))
    young.checks.append(eq.Check("impact speed", v, 61.0, math.inf, "m/s", False))
    estimates.append(young)

    messages = [
        f"{e.name}: {c.quantity} = {c.value:.4g}{' ' + c.unit if c.unit else ''} lies outside its range"
        f" {c.low:g}-{c.high:g}{' ' + c.unit if c.unit else ''}"
        + ("" if c.checked else " (a compilation's range, not checked against the source)")
        for e in estimates
        for c in e.checks
        if not c.inside
    ]
    return Formulas(i, estimates, messages)


def formulas_report(result: Formulas, scene_name: str) -> Report:
    """The printed table: each formula's depth, its scabbing and perforation thicknesses, whether the scene lies
    inside every range it checks, and its source."""
    rows = [
        [
            e.name,
            number_cell(e.depth, ".3f"),
            number_cell(e.scabbing, ".3f"),
            number_cell(e.perforation, ".3f"),
            "yes" if e.valid else "no",
            e.source,
        ]
        for e in result.estimates
    ]
    header = ["formula", "depth (m)", "scabbing (m)", "perforation (m)", "inside its ranges", "source"]
    lines = [f"# Empirical formulas: {scene_name}", "", *markdown_table(header, rows), "", *result.messages]
    return Report("formulas", "\n".join(lines) + "\n", record=result.as_dict())


def formula_rows(series: Series, scenes: Sequence[Scene]) -> tuple[list[dict], list[str]]:
    """Each formula's depth for each measured depth of ``series``, its shots run as ``scenes`` (in its order; more
    are ignored): a row per shot and formula of a depth (``error_percent`` of the measurement, ``valid``); and a line
    for each shot the formulas do not describe."""
    rows, refused = [], []
    for shot, scene in zip(series.shots, scenes):
        for measured in (m.value for m in shot.measurements if m.quantity == "depth"):
            label, group = shot.label, shot.group
            try:
                result = formulas(scene)
            except InputError as error:
                refused.append(f"{label}: {error}")
                continue
            for e in result.estimates:
                if e.depth is None:  # a thickness only
                    continue
                rows.append(
                    {
                        "label": label,
                        "group": group,
                        "formula": e.name,
                        "predicted": e.depth,
                        "measured": measured,
                        "error_percent": 100.0 * (e.depth - measured) / abs(measured),
                        "residual_sigmas": None,
                        "valid": e.valid,
                    }
                )
    return rows, refused
