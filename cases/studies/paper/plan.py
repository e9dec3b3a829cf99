"""The runs of the paper's study, described as data: which projectile, which disturbance, which speeds."""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

from ... import scene_path
from ..engine.sweep import Sweep, Variation, grid

__all__ = [
    "STUDY_NUMERICS",
    "FINE_NUMERICS",
    "PAPER_RATIOS",
    "P3",
    "NUMBERED",
    "SCAN",
    "WIDE",
    "PUBLISHED_TABLE4_P3",
    "INERTIA_SCALES",
    "OBLIQUE",
    "VARIANTS",
    "VARIANT_SPEEDS",
    "RunGroup",
    "label",
    "study_base",
    "critical_bases",
    "speed_groups",
    "variant_groups",
    "around",
]

# Dormand-Prince at rtol 1e-8: on #3 at 900 and 1120 m/s as accurate in time as RK4 at 2e-5 s (20 mm) and
# 1e-5 s (10 mm), the study's fixed steps until November 2026, in depth, path and axis turn, with 3-8 times
# fewer load evaluations (docs/performance.md, "Study numerics")
STUDY_NUMERICS = {"numerics.mesh_size": 0.02, "numerics.integrator": "dopri54", "numerics.rtol": 1e-8}
FINE_NUMERICS = {"numerics.mesh_size": 0.01, "numerics.integrator": "dopri54", "numerics.rtol": 1e-8}
PAPER_RATIOS = (0.4448, 0.4745, 0.5042, 0.5339, 0.5636, 0.5933, 0.6230)
P3 = 0.5636
NUMBERED = {0.4448: "#1", 0.5042: "#2", 0.5636: "#3", 0.6230: "#4"}
SCAN = list(range(400, 2001, 100))
WIDE = list(range(200, 1601, 200))
PUBLISHED_TABLE4_P3 = {1100: 888, 1120: 326, 1140: 324, 1160: 323, 1180: 322, 1200: 322}
INERTIA_SCALES = (0.67, 1.5)
# 1 degree of attack with these oblique angles (deg), on these projectiles
OBLIQUE = {10: PAPER_RATIOS, 20: (P3,), 30: (P3,)}

VARIANTS: dict[str, dict[str, Any]] = {
    "paper default": {},
    "Coulomb friction, mu = 0.10": {"effects.friction.model": "coulomb", "effects.friction.coefficient": 0.1},
    "capped friction, tau_s = 10 MPa": {"effects.friction": {"model": "capped", "coefficient": 0.1, "cap": 10e6}},
    "conical nose, 12.92 deg": {"projectile.nose": {"shape": "cone", "half_angle": 12.92}},
    "soil, dynamic cavity expansion": {"target.law": "soil_dynamic_cavity_expansion"},
    "softer soil": {"target.law": "softer_soil"},
}
VARIANT_SPEEDS = list(range(200, 2001, 200))


def label(ratio: float) -> str:
    """``#3 (56.36 %)`` for the numbered projectiles, ``47.45 %`` for the others."""
    tag = NUMBERED.get(ratio)
    return f"{tag} ({100 * ratio:.2f} %)" if tag else f"{100 * ratio:.2f} %"


def study_base(ratio: float, overrides: dict[str, Any] | None = None) -> Sweep:
    """Projectile ``paper_p3`` with the centre of mass at ``ratio`` of the length, the study numerics and
    ``overrides``."""
    return Sweep.from_file(
        scene_path("paper_p3"),
        {**STUDY_NUMERICS, "projectile.centre_of_mass_ratio": ratio, "name": "paper", **(overrides or {})},
    )


@dataclass(frozen=True)
class RunGroup:
    """Runs of one projectile under one disturbance at several impact speeds (m/s).

    ``kind`` names the disturbance (``attack 1``, ``attack 5``, ``attack 1, oblique 10``, ...);
    ``overrides`` are applied over the study's base scene; ``fine`` uses the shipped (finer)
    numerics instead of the study's.
    """

    kind: str
    ratio: float
    speeds: tuple[float, ...]
    overrides: dict[str, Any] = field(default_factory=dict)
    fine: bool = False

    def base(self) -> Sweep:
        if self.fine:
            return Sweep.from_file(
                scene_path("paper_p3"), {**FINE_NUMERICS, "projectile.centre_of_mass_ratio": self.ratio}
            )
        return study_base(self.ratio, self.overrides)

    def variations(self) -> list[Variation]:
        return grid({"impact.speed": list(self.speeds)})


def critical_bases() -> list[Sweep]:
    """The critical-speed searches: every projectile at 1 degree, then #3 with scaled transverse inertia."""
    return [study_base(r) for r in PAPER_RATIOS] + [
        study_base(P3, {"projectile.transverse_inertia_scale": k}) for k in INERTIA_SCALES
    ]


def around(critical: float | None) -> list[float]:
    """Six impact speeds 20 m/s apart around a critical speed (1000 m/s when none was found)."""
    centre = 20 * round((critical or 1000) / 20)
    return [centre + d for d in (-40, -20, 0, 20, 40, 60)]


def speed_groups(critical: list[float | None]) -> list[RunGroup]:
    """Every group of the study once the critical speeds are known, in the order they run.

    Each projectile at 1 degree around its critical speed and at 5 degrees over :data:`WIDE`;
    #3 at the paper's Table 4 speeds; 1 degree with the oblique angles of :data:`OBLIQUE`; an
    oblique angle alone (does it disturb less than an attack angle?); and #3 near its critical
    speed at the shipped (finer) numerics, the numerical check.
    """
    groups: list[RunGroup] = []
    for r, c in zip(PAPER_RATIOS, critical):
        groups.append(RunGroup("attack 1", r, tuple(around(c))))
        groups.append(RunGroup("attack 5", r, tuple(WIDE), {"impact.attack_angle": 5}))
    groups.append(RunGroup("paper speeds", P3, tuple(PUBLISHED_TABLE4_P3)))
    for angle, which in OBLIQUE.items():
        groups += [
            RunGroup(f"attack 1, oblique {angle}", r, tuple(WIDE), {"impact.oblique_angle": angle}) for r in which
        ]
    for angle in (10, 30):
        groups.append(
            RunGroup(
                f"attack 0, oblique {angle}", P3, tuple(WIDE), {"impact.attack_angle": 0, "impact.oblique_angle": angle}
            )
        )
    p3_speeds = around(critical[PAPER_RATIOS.index(P3)])
    groups.append(RunGroup("fine numerics", P3, (p3_speeds[1], p3_speeds[3]), fine=True))
    return groups


def variant_groups() -> list[RunGroup]:
    """Every variant of :data:`VARIANTS`, every projectile, at 1 degree over :data:`VARIANT_SPEEDS`."""
    return [
        RunGroup(name, r, tuple(VARIANT_SPEEDS), overrides)
        for name, overrides in VARIANTS.items()
        for r in PAPER_RATIOS
    ]
