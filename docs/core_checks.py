"""Print the core's accuracy figures against independent truth (docs/validation.md).

Run with ``.venv/bin/python -m docs.core_checks [SECTION ...]`` from the repository root;
the sections are ``mass``, ``surface``, ``impact`` and ``table3`` (all by default), each
printed as markdown under no heading, as docs/validation.md embeds them.  The mass table,
with meshes down to 5 mm, takes most of the time (docs/validation.md gives it).
"""

from __future__ import annotations

import math
import sys

import numpy as np

from cases import history_table, load_scene, run_scene, scene_path, summarise
from cases.reference.normal_impact import axial_depth_1d, embedded_axial_force
from fem_loads import DAFLLoads, mass_properties, resistance_law, surface_quadrature
from mesh import (
    BODY,
    COUNTERWEIGHT,
    Interior,
    OgiveNose,
    Profile,
    ProjectileGeometry,
    analytic_mass_properties,
    build_mesh,
    place_counterweight,
)


def mass_table() -> None:
    print("| body | h (m) | tetrahedra (thousands) | volume | mass | Lc | axial I | transverse I |")
    print("|---|---|---|---|---|---|---|---|")
    paper = Profile(0.155, 0.93, OgiveNose(5.0))
    interior = Interior(0.01, 0.02)
    span = place_counterweight(paper, interior, 7850, 18000, 75.67, 0.5636 * 0.93)
    bodies = {
        "#3 with counterweight": ProjectileGeometry(paper, interior, span),
        "solid ogive CRH 5": ProjectileGeometry(paper),
    }
    for name, geometry in bodies.items():
        exact = analytic_mass_properties(geometry, 7850, 18000)
        for h in (0.02, 0.01, 0.005):
            mesh = build_mesh(geometry, h, 2)
            fem = mass_properties(mesh, {BODY: 7850.0, COUNTERWEIGHT: 18000.0})
            errs = [
                fem.volume / exact.volume,
                fem.mass / exact.mass,
                fem.centre_from_tip / exact.centre_from_tip,
                fem.axial_inertia / exact.axial_inertia,
                fem.transverse_inertia / exact.transverse_inertia,
            ]
            cells = " | ".join(f"{e - 1:+.1e}" for e in errs)
            # gmsh's HXT mesher can differ by a few tetrahedra from one process to another
            print(f"| {name} | {h} | {len(mesh.tetra) / 1000:.0f} | {cells} |")


def surface_table() -> None:
    print("| order | normals | h (m) | points | sum n dA / (pi a^2) | volume | area | axial force, 1200 m/s |")
    print("|---|---|---|---|---|---|---|---|")
    profile = Profile(0.155, 0.93, OgiveNose(5.0))
    volume = analytic_mass_properties(ProjectileGeometry(profile), 1.0).volume
    law = resistance_law("soil")
    down = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
    for order in (1, 2):
        for model in ("mesh", "exact"):
            for h in (0.02, 0.01, 0.005):
                mesh = build_mesh(ProjectileGeometry(profile), h, order)
                q = surface_quadrature(mesh, np.zeros(3), profile, model)
                closure = np.abs(q.normals.T @ q.weights).max() / (math.pi * profile.radius**2)
                force, _ = DAFLLoads(q, law)(np.array([0, 0, -10.0]), np.array([0, 0, -1200.0]), down, np.zeros(3))
                axial = force[2] / embedded_axial_force(profile, law, 1200.0) - 1
                # below 1e-12 the closure is round-off, whose digits vary with the machine
                shown = f"{closure:.1e}" if closure > 1e-12 else "< 1e-12"
                print(
                    f"| {order} | {model} | {h} | {len(q)} | {shown} | {q.enclosed_volume() / volume - 1:+.1e}"
                    f" | {q.area / profile.surface_area() - 1:+.1e} | {axial:+.2e} |"
                )


def normal_impact() -> None:
    scene = load_scene(scene_path("forrestal_luk_test2"))
    result = run_scene(scene)
    record = summarise(result)
    law = scene.target.build()
    reference, v1 = axial_depth_1d(
        result.prepared.profile,
        law,
        result.prepared.mass.mass,
        280.0,
        scene.stop_speed,
        **scene.effects.contact_ramp,
    )
    print(
        f"3-D depth {record.depth:.5f} m; 1-D with exact nose entry and the same contact width {reference:.5f} m;"
        f" relative difference {record.depth / reference - 1:+.2e}; speed at full embedding {v1:.3f} m/s"
    )


def table3() -> None:
    print("| test | measured (m) | paper (m) | ours, path length (m) | vs paper | ours, tip depth (m) |")
    print("|---|---|---|---|---|---|")
    published = {2: (4.98, 5.05), 3: (5.18, 5.00), 4: (5.18, 5.05), 5: (5.02, 5.01), 6: (4.82, 5.00)}
    for test, (measured, paper) in published.items():
        result = run_scene(load_scene(scene_path(f"forrestal_luk_test{test}")))
        record = summarise(result, history_table(result))
        print(
            f"| {test} | {measured} | {paper} | {record.path_length:.3f} | {record.path_length / paper - 1:+.2%}"
            f" | {record.depth:.3f} |"
        )


SECTIONS = {"mass": mass_table, "surface": surface_table, "impact": normal_impact, "table3": table3}

if __name__ == "__main__":
    chosen = sys.argv[1:] or list(SECTIONS)
    unknown = [name for name in chosen if name not in SECTIONS]
    if unknown:
        sys.exit(f"docs.core_checks: unknown section {unknown[0]!r}: choose from {', '.join(SECTIONS)}")
    for number, name in enumerate(chosen):
        if number:
            print()
        SECTIONS[name]()
