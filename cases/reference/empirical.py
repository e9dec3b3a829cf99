"""The empirical equations of the field for a hard projectile against concrete: depth of penetration, and the
scabbing and perforation thicknesses that go with it.

Each function takes SI values: the mass ``M`` (kg), the shank diameter ``d`` (m), the impact speed ``V`` (m/s),
the unconfined compressive strength ``fc`` (Pa) and the concrete's density ``rho`` (kg/m^3), for a normal impact
into a target thick enough to be treated as semi-infinite.  Where a source gives the formula in English units
(lb, in, ft/s, psi), the SI constant is that form converted, and the tests check the two against each other.

* **Modified NDRC** (Kennedy 1976, from the NDRC's 1946 formula):
  ``G = 3.8e-5 N* M / (d sqrt(fc)) (V/d)^1.8``, ``x/d = 2 sqrt(G)`` for ``G <= 1``, else ``G + 1``.
* **ACE** (US Army Corps of Engineers 1946): ``x/d = 3.5e-4 / sqrt(fc) (M/d^3) d^0.215 V^1.5 + 0.5``.
* **UKAEA** (Barr 1990): the NDRC's ``G``; ``x/d = 0.275 - sqrt(0.0756 - G)`` for ``G <= 0.0726``,
  ``sqrt(4G - 0.242)`` up to ``G = 1.0605``, then ``G + 0.9395``.
* **Li and Chen** (2003), dimensionless: the impact function ``I = M V^2 / (S fc d^3)`` with
  ``S = 72 (fc/MPa)^-0.5`` and the geometry function ``N = M / (N* rho d^3)``; a crater of depth ``k d``
  (``k = 0.707 + h/d``, ``h`` the nose length), then a tunnel: ``x/d = sqrt((1 + k pi/4N)/(1 + I/N) 4kI/pi)``
  for ``x/d <= k``, else ``(2N/pi) ln((1 + I/N)/(1 + k pi/4N)) + k``.  Its tunnel is Forrestal's cavity
  expansion closed form with that crater.
* **Young** (Sandia 1997), for concrete with the S-number from ``fc``:
  ``D = 1.8e-5 S N K (M/A)^0.7 (V - 30.5)`` (``V >= 61`` m/s) with the nose performance coefficient ``N``, the
  mass factor ``K = 0.46 M^0.15`` below 182 kg, and ``S = 0.085 Ke (11 - P) (tc Tc)^-0.06 (35/(fc/MPa))^0.3``.
* **Scabbing** (NDRC and ACE): ``ts/d = 7.91 X - 5.06 X^2`` for ``X = x/d < 0.65``, ``2.12 + 1.36 X`` up to 11.75.
* **Perforation**: NDRC and ACE ``tp/d = 3.19 X - 0.718 X^2`` for ``X <= 1.35``, ``1.32 + 1.24 X`` up to 13.5;
  Degen (1980) ``tp/d = 2.2 X - 0.3 X^2`` for ``X <= 1.52``, ``0.69 + 1.29 X`` for ``2.65 <= tp/d <= 18``.

Which of these were read in a source and which come from a compilation is said in the docs (the formulas'
page), per formula; :data:`SOURCES` names each one's original and the compilation checked.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

__all__ = [
    "Check",
    "Estimate",
    "NDRC_NOSE_FACTORS",
    "SOURCES",
    "ndrc_g",
    "ndrc_depth",
    "ace_depth",
    "ukaea_depth",
    "li_chen_depth",
    "young_concrete_s_number",
    "young_nose_coefficient",
    "young_mass_factor",
    "young_depth",
    "scabbing_thickness",
    "perforation_thickness",
    "degen_perforation_thickness",
]

MPA = 1e6

#: the NDRC's nose shape factor N* by the kind of nose it names (Kennedy 1976)
NDRC_NOSE_FACTORS = {"flat": 0.72, "blunt": 0.84, "spherical": 1.0, "very_sharp": 1.14}

SOURCES = {
    "modified NDRC": "Kennedy (1976), Nucl. Eng. Des. 37:183-203; as given by DOE-STD-3014 App. C and Li et al. (2005)",
    "ACE": "US Army Corps of Engineers (1946); as given by Li et al. (2005), Int. J. Impact Eng. 32:224-284",
    "UKAEA": "Barr (1990), UKAEA SRD guidelines; as given by Li et al. (2005)",
    "Li and Chen": "Li and Chen (2003), Int. J. Impact Eng. 28:93-116",
    "Young": "Young (1997), SAND97-2426, Sandia National Laboratories",
    "NDRC scabbing": "Kennedy (1976); DOE-STD-3014 App. C, eq. C6-5 and C6-6",
    "NDRC perforation": "Kennedy (1976); as given by Li et al. (2005)",
    "Degen perforation": "Degen (1980), Nucl. Eng. Des. 59:249-268; DOE-STD-3014 App. C, eq. C6-13 and C6-14",
}


@dataclass(frozen=True)
class Check:
    """One quantity of a scene checked against the range of a formula's data or of its validity; ``checked``:
    the range was read in the formula's source (else it comes from a compilation not checked against it)."""

    quantity: str
    value: float
    low: float
    high: float
    unit: str
    checked: bool

    @property
    def inside(self) -> bool:
        return self.low <= self.value <= self.high

    def as_dict(self) -> dict:
        return {
            "quantity": self.quantity,
            "value": self.value,
            "low": self.low,
            "high": self.high,
            "unit": self.unit,
            "inside": self.inside,
            "checked": self.checked,
        }


@dataclass
class Estimate:
    """What a formula says of a scene: the depth (m; None for a formula of a thickness only) and, where it gives
    them, the scabbing and perforation thicknesses (m); ``valid`` when every check lies inside its range."""

    name: str
    depth: float | None
    source: str
    checks: list[Check] = field(default_factory=list)
    scabbing: float | None = None
    perforation: float | None = None

    @property
    def valid(self) -> bool:
        return all(check.inside for check in self.checks)

    def as_dict(self) -> dict:
        return {
            "name": self.name,
            "depth": self.depth,
            "valid": self.valid,
            "checks": [check.as_dict() for check in self.checks],
            "scabbing": self.scabbing,
            "perforation": self.perforation,
            "source": self.source,
        }


def ndrc_g(mass: float, diameter: float, speed: float, strength: float, nose_factor: float) -> float:
    """The NDRC's penetration function ``G = 3.8e-5 N* M / (d sqrt(fc)) (V/d)^1.8`` (SI, ``fc`` in Pa)."""
    return 3.8e-5 * nose_factor * mass / (diameter * math.sqrt(strength)) * (speed / diameter) ** 1.8


def ndrc_depth(mass: float, diameter: float, speed: float, strength: float, nose_factor: float) -> float:
    """The modified NDRC's depth of penetration (m)."""
    g = ndrc_g(mass, diameter, speed, strength, nose_factor)
    return diameter * (2.0 * math.sqrt(g) if g <= 1.0 else g + 1.0)


def ace_depth(mass: float, diameter: float, speed: float, strength: float) -> float:
    """The ACE formula's depth of penetration (m): ``x/d = 3.5e-4 / sqrt(fc) (M/d^3) d^0.215 V^1.5 + 0.5``."""
    return diameter * (3.5e-4 / math.sqrt(strength) * mass / diameter**3 * diameter**0.215 * speed**1.5 + 0.5)


def ukaea_depth(mass: float, diameter: float, speed: float, strength: float, nose_factor: float) -> float:
    """The UKAEA formula's depth of penetration (m), on the NDRC's ``G``."""
    g = ndrc_g(mass, diameter, speed, strength, nose_factor)
    if g <= 0.0726:
        ratio = 0.275 - math.sqrt(0.0756 - g)
    elif g <= 1.0605:
        ratio = math.sqrt(4.0 * g - 0.242)
    else:
        ratio = g + 0.9395
    return diameter * ratio


def li_chen_depth(
    mass: float, diameter: float, speed: float, strength: float, density: float, nose_factor: float, nose_length: float
) -> float:
    """Li and Chen's depth of penetration (m): ``nose_factor`` is the cavity-expansion nose factor ``N*`` (a tangent
    ogive of CRH ``psi``: ``(8 psi - 1)/(24 psi^2)``), ``nose_length`` ``h`` (m)."""
    s = 72.0 * (strength / MPA) ** -0.5
    impact = mass * speed**2 / (s * strength * diameter**3)
    geometry = mass / (nose_factor * density * diameter**3)
    k = 0.707 + nose_length / diameter
    crater = 1.0 + k * math.pi / (4.0 * geometry)
    if impact <= math.pi * k / 4.0:  # x/d <= k: the crater phase alone (the two forms meet at I = pi k / 4)
        ratio = math.sqrt(crater / (1.0 + impact / geometry) * 4.0 * k * impact / math.pi)
    else:
        ratio = 2.0 * geometry / math.pi * math.log((1.0 + impact / geometry) / crater) + k
    return diameter * ratio


def young_concrete_s_number(
    strength: float,
    reinforcement: float = 0.0,
    cure_years: float = 1.0,
    thickness_calibres: float = 6.0,
    width_calibres: float = math.inf,
    reinforced: bool = True,
) -> float:
    """Young's S-number of concrete: ``S = 0.085 Ke (11 - P) (tc Tc)^-0.06 (35/(fc/MPa))^0.3`` with ``P`` the
    volume percentage of reinforcement, ``tc`` the cure time (years, at most 1), ``Tc`` the thickness in projectile
    diameters (0.5-6) and ``Ke = (F / W1)^0.3`` for a target ``W1`` diameters wide, narrower than ``F`` (20
    reinforced, 30 plain), else 1."""
    tc = min(cure_years, 1.0)
    tk = min(max(thickness_calibres, 0.5), 6.0)
    limit = 20.0 if reinforced else 30.0
    ke = (limit / width_calibres) ** 0.3 if width_calibres < limit else 1.0
    return 0.085 * ke * (11.0 - reinforcement) * (tc * tk) ** -0.06 * (35.0 / (strength / MPA)) ** 0.3


def young_nose_coefficient(kind: str, nose_length: float, diameter: float) -> float:
    """Young's nose performance coefficient: ``0.18 L/d + 0.56`` for a tangent ogive, ``0.25 L/d + 0.56`` for a
    cone (``L`` the nose length), 0.56 for a flat nose."""
    slope = {"ogive": 0.18, "cone": 0.25, "flat": 0.0}[kind]
    return slope * nose_length / diameter + 0.56


def young_mass_factor(mass: float) -> float:
    """Young's mass scaling factor for a target that is not soil: ``0.46 M^0.15`` below 182 kg, else 1."""
    return 0.46 * mass**0.15 if mass < 182.0 else 1.0


def young_depth(mass: float, diameter: float, speed: float, s_number: float, nose_coefficient: float) -> float:
    """Young's depth of penetration (m) for ``V >= 61`` m/s: ``D = 1.8e-5 S N K (M/A)^0.7 (V - 30.5)``."""
    area = math.pi * diameter**2 / 4.0
    factor = young_mass_factor(mass)
    return 1.8e-5 * s_number * nose_coefficient * factor * (mass / area) ** 0.7 * (speed - 30.5)


def scabbing_thickness(depth: float, diameter: float) -> float:
    """The NDRC's (and ACE's) scabbing thickness (m) for a depth of penetration ``x`` (m)."""
    x = depth / diameter
    return diameter * (7.91 * x - 5.06 * x**2 if x < 0.65 else 2.12 + 1.36 * x)


def perforation_thickness(depth: float, diameter: float) -> float:
    """The NDRC's (and ACE's) perforation thickness (m) for a depth of penetration ``x`` (m)."""
    x = depth / diameter
    return diameter * (3.19 * x - 0.718 * x**2 if x <= 1.35 else 1.32 + 1.24 * x)


def degen_perforation_thickness(depth: float, diameter: float) -> float:
    """Degen's perforation thickness (m) for the NDRC's depth of penetration ``x`` (m)."""
    x = depth / diameter
    return diameter * (2.2 * x - 0.3 * x**2 if x <= 1.52 else 0.69 + 1.29 * x)
