"""A shipped test series: each shot predicted by ``penetrate validate``, by the 1-D integration of the embedded
nose and by a closed form, against the measurement: the tables of docs/validation.md.  Run from the repository
root::

    python -m docs.validation.series forrestal1996_concrete

The 1-D integration (:func:`cases.reference.normal_impact.axial_depth_1d`) is the model's own straight shot: the
axial equation with the exact embedded nose area, the same law, mass and stop speed.  The closed form is the
one the series' source uses: for concrete Forrestal et al.'s, with a crater of depth ``2d`` whose force grows
linearly with depth, ``X = 2d + (2m / (pi d^2 N rho)) ln(1 + N rho V1^2 / (S f'c))`` with
``V1^2 = (m V0^2 - pi d^3 S f'c / 2) / (m + pi d^3 N rho / 2)``; for the soil the tunnel alone entered at the
impact speed, ``L_nose + m / (2 pi a^2 N B rho_0) ln(1 + N B rho_0 V0^2 / (A sigma_0))``.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from cases import prepare_projectile
from cases.reference.normal_impact import closed_form_depth, scene_depth_1d
from cases.run import RunStore
from cases.studies import Pool
from cases.studies.measured.series import read_series
from cases.studies.measured.validate import validate


def forrestal_concrete(diameter: float, nose_factor: float, law, mass: float, speed: float) -> float:
    """Forrestal et al.'s depth (m) with the crater of depth 2d (``law``: ``S f'c`` and ``rho`` as ``c0``, ``c2``)."""
    strength, density = law.c0, law.c2
    crater = math.pi * diameter**3 / 2
    v1_squared = (mass * speed**2 - crater * strength) / (mass + crater * nose_factor * density)
    tunnel = 2 * mass / (math.pi * diameter**2 * nose_factor * density)
    return 2 * diameter + tunnel * math.log1p(nose_factor * density * v1_squared / strength)


def main(name: str) -> None:
    series = read_series(name)
    validation = validate(series, None, RunStore(f"runs/series-{name}-store"), Pool(progress=False), curve_points=0)
    scenes = validation_scenes(series)
    concrete = all(getattr(scene.target.law, "model", None) == "concrete" for scene in scenes)
    closed_name = "Forrestal's closed form (crater 2d)" if concrete else "closed form (tunnel at V0)"
    print(f"| shot | impact speed (m/s) | measured (m) | penetrate (m) | 1-D (m) | {closed_name} (m) |")
    print("|---|---|---|---|---|---|")
    errors: dict[str, list[float]] = {"penetrate": [], "1-D": [], "closed": []}
    for row, scene in zip(validation.rows, scenes):
        prepared = prepare_projectile(scene)
        law, mass, speed = scene.target.build(), prepared.mass.mass, scene.impact.speed
        one_d = scene_depth_1d(scene, prepared)
        profile = prepared.profile
        if concrete:
            closed = forrestal_concrete(2 * profile.radius, profile.nose_factor(), law, mass, speed)
        else:
            closed = profile.nose_length + closed_form_depth(profile, law, mass, speed)
        measured = row["measured"]
        cells = []
        for key, value in (("penetrate", row["predicted"]), ("1-D", one_d), ("closed", closed)):
            error = 100 * (value - measured) / measured
            errors[key].append(error)
            cells.append(f"{value:.3f} ({error:+.1f} %)")
        print(f"| {row['label']} | {speed:g} | {measured:.3f} | " + " | ".join(cells) + " |")
    means = " | ".join(f"{np.mean(np.abs(e)):.1f} % ({np.mean(e):+.1f} %)" for e in errors.values())
    print(f"| mean abs error (bias) | | | {means} |")


def validation_scenes(series):
    """Each shot's resolved scene, as the validation ran it."""
    return series.sweep().scenes


if __name__ == "__main__":
    main(sys.argv[1] if len(sys.argv) > 1 else "forrestal1996_concrete")
