"""The figures of docs/rendering.md's example: projectile #3 at 1120 m/s with the shipped numerics.

Run: ``.venv/bin/python -m docs.rendering.example`` (about 15 s).  Prints the run's summary
line, the table of the default instants (time, speed, attack angle, the largest facet
``sigma_n`` and the windward / leeward means) and the tip check at the embedded instant: the
hottest facet's mean against the closed form ``A sigma_0 + B rho_0 (V sin theta_tip)^2`` at the
tip of the CRH 5 ogive (the facet mean lies below the value at the tip point itself).
"""

from __future__ import annotations

import math

import numpy as np

from cases import load_scene, run_scene, scene_path
from cases.run import convergence_speed, summarise
from cases.scene.target import build_law
from cases.viz.field import FieldEvaluator, key_instants

WINDWARD_COSINE = math.cos(math.radians(73.0))
NAMES = {"embedded": "nose embedded", "peak": "peak attack angle", "converged": "converged", "end": "end"}


def facet_normals(evaluator: FieldEvaluator) -> np.ndarray:
    """Body-frame outward normal of each facet: the area-weighted mean of its points' normals."""
    per_facet = evaluator.surface.points_per_facet  # the quadrature's points lie facet by facet (cases.viz.field)
    weights = evaluator.prepared.quadrature.weights.reshape(-1, per_facet)
    normals = evaluator.prepared.quadrature.normals.reshape(*weights.shape, 3)
    mean = (normals * weights[..., None]).sum(axis=1)
    return mean / np.linalg.norm(mean, axis=1, keepdims=True)


def main() -> None:
    scene = load_scene(scene_path("paper_p3"), {"impact.speed": 1120})
    result = run_scene(scene)
    summary = summarise(result)
    evaluator = FieldEvaluator(result)
    normals = facet_normals(evaluator)
    print(
        f"The run is {'unstable' if summary.axis_angle_change >= 30 else 'stable'}: the attack angle "
        f"peaks at {summary.max_attack_angle:.1f} degrees, the path turns by {summary.axis_angle_change:.0f} "
        f"degrees, the attack angle converges at {convergence_speed(evaluator.history):.0f} m/s and the run ends "
        f"({summary.end_reason}) at {summary.final_speed:.0f} m/s; {len(evaluator)} recorded steps, "
        f"{evaluator.surface.n_facets} facets drawn as {len(evaluator.surface.triangles)} triangles."
    )
    print()
    print(
        "| instant | t (ms) | speed (m/s) | attack (deg) | largest facet `sigma_n` (MPa) "
        "| windward / leeward mean (MPa) |"
    )
    print("|---|---|---|---|---|---|")
    embedded = None
    for name, row in key_instants(evaluator).items():
        field = evaluator.at(row)
        if name == "embedded":
            embedded = field
        if not field.sigma_n.any():
            print(
                f"| {NAMES[name]} | {field.time * 1e3:.2f} | {field.speed:.0f} | {field.attack_angle:+.2f} "
                "| 0 (out of the target) | - |"
            )
            continue
        # the transverse velocity in the body frame sets the windward side
        velocity = field.rotation.T @ field.velocity
        transverse = velocity - velocity[0] * np.array([1.0, 0.0, 0.0])
        direction = transverse / np.linalg.norm(transverse)
        facing = normals @ direction
        hottest = int(np.argmax(field.sigma_n))
        where = " (the tip)" if hottest in np.argsort(-normals[:, 0])[:50] else ""
        print(
            f"| {NAMES[name]} | {field.time * 1e3:.2f} | {field.speed:.0f} | {field.attack_angle:+.2f} "
            f"| {field.sigma_n[hottest] / 1e6:.1f}{where} "
            f"| {field.sigma_n[facing > WINDWARD_COSINE].mean() / 1e6:.1f} / "
            f"{field.sigma_n[facing < -WINDWARD_COSINE].mean() / 1e6:.1f} |"
        )
    if embedded is not None:
        law = build_law(scene.target.law)
        tip_angle = math.asin(math.sqrt(1.0 - ((5.0 - 0.5) / 5.0) ** 2))  # CRH 5: cos(theta) = (psi - 1/2) / psi
        tip = law.c0 + law.c2 * (embedded.speed * math.sin(tip_angle)) ** 2
        print()
        print(
            f"At the embedded instant the hottest facet's mean is {embedded.sigma_n.max() / 1e6:.1f} MPa against "
            f"`A sigma_0 + B rho_0 (V sin {math.degrees(tip_angle):.1f} deg)^2 = {tip / 1e6:.0f} MPa` at the tip "
            "point itself."
        )


if __name__ == "__main__":
    main()
