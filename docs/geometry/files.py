"""Projectiles from files against the analytic scenes (docs/evidence-geometry.md): what each kind of file costs in
accuracy.

Run from the repository root: ``python -m docs.geometry.files facets`` (about three minutes: the 5 mm meshes) or
``python -m docs.geometry.files files`` (about a minute).  The bodies are written by gmsh's own OpenCASCADE
primitives (``docs/geometry/cad_bodies.py``, independent of ``mesh/``) into a temporary folder and read back through
``projectile.geometry``; every run is test 2's shot (or its cone-nosed twin) at the shipped numerics unless
the table says otherwise.  Prints a markdown table.

* ``facets``: the depth of test 2 with the body as a first-order (flat facets) and a second-order volume
  mesh with their own normals, at 20, 10 and 5 mm, against the exact 1-D integration of the axial problem
  with the same contact width (``cases.reference.normal_impact``): what the facets cost against the truth.
* ``files``: STEP, BREP and IGES files in several units, a cone-nosed STEP file and volume meshes: the
  largest error of their mass properties and their depth against the analytic scene.
"""

from __future__ import annotations

import contextlib
import os
import sys
import tempfile
from pathlib import Path

from cases import load_scene, run_scene, scene_path, summarise
from cases.reference.normal_impact import axial_depth_1d
from docs.geometry.cad_bodies import write_body, write_volume_mesh

TEST2 = scene_path("forrestal_luk_test2")
CONE = {"projectile.nose": {"shape": "cone", "half_angle": 12.0}}


def _run(overrides: dict):
    with _quiet():  # reading a mesh file, gmsh writes empty lines to the standard output
        result = run_scene(load_scene(TEST2, overrides))
    return result.prepared.mass, summarise(result).depth


@contextlib.contextmanager
def _quiet():
    """gmsh's OpenCASCADE writers print to the standard output, which is this script's table: send it away."""
    sys.stdout.flush()
    kept = os.dup(1)
    try:
        with open(os.devnull, "w") as null:
            os.dup2(null.fileno(), 1)
            yield
    finally:
        os.dup2(kept, 1)
        os.close(kept)


def facets(folder: Path) -> None:
    scene = load_scene(TEST2)
    reference, _ = axial_depth_1d(
        scene.projectile.profile(),
        scene.target.build(),
        scene.projectile.mass,
        scene.impact.speed,
        scene.stop_speed,
        **scene.effects.contact_ramp,
    )
    print("| mesh | 20 mm | 10 mm | 5 mm |")
    print("|---|---|---|---|")
    for order, label in (
        (1, "4-node tetrahedra (flat facets), own normals"),
        (2, "10-node tetrahedra (curved facets), own normals"),
    ):
        cells = []
        for size in (0.02, 0.01, 0.005):
            with _quiet():
                path = write_volume_mesh(folder / f"o{order}_{size:g}.msh", size, order=order)
            _, depth = _run(
                {
                    "projectile.geometry": {"file": str(path)},
                    "numerics.normals": "mesh",
                    "numerics.geometry_order": order,
                    "numerics.mesh_size": size,
                }
            )
            cells.append(f"{100 * (depth / reference - 1):+.2g} %")
        print(f"| {label} | " + " | ".join(cells) + " |", flush=True)


def _worst(got, want) -> float:
    return max(
        abs(getattr(got, key) / getattr(want, key) - 1)
        for key in ("mass", "centre_from_tip", "axial_inertia", "transverse_inertia")
    )


def files(folder: Path) -> None:
    with _quiet():
        rows = _bodies(folder)
    print(
        "| file | largest mass-property error (mass, centre, both inertias) | depth (m) | analytic scene (m) |"
        " difference |"
    )
    print("|---|---|---|---|---|")
    for label, path, geometry, nose, numerics in rows:
        props, depth = _run({"projectile.geometry": {"file": str(path), **geometry}, **numerics})
        want, analytic = _run(nose)
        print(
            f"| {label} | {_worst(props, want):.1e} | {depth:.4f} | {analytic:.4f} | {depth / analytic - 1:+.1e} |",
            flush=True,
        )


def _bodies(folder: Path) -> list:
    return [
        ("STEP in mm, exact normals", write_body(folder / "body.step", scale=1e-3), {"unit": "mm"}, {}, {}),
        ("BREP in cm, exact normals", write_body(folder / "body.brep", scale=1e-2), {"unit": "cm"}, {}, {}),
        (
            "IGES in mm (loose faces, sewn), exact normals",
            write_body(folder / "body.iges", scale=1e-3),
            {"unit": "mm"},
            {},
            {},
        ),
        ("STEP, cone nose (12 deg half angle)", write_body(folder / "cone.step", half_angle=12.0), {}, CONE, {}),
        ("STEP in mm, mesh normals", folder / "body.step", {"unit": "mm"}, {}, {"numerics.normals": "mesh"}),
        ("`.msh`, 10-node, 10 mm", write_volume_mesh(folder / "body.msh", 0.01), {}, {}, {"numerics.normals": "mesh"}),
        ("`.vtu`, 10-node, 10 mm", write_volume_mesh(folder / "body.vtu", 0.01), {}, {}, {"numerics.normals": "mesh"}),
    ]


def main() -> None:
    table = sys.argv[1] if len(sys.argv) > 1 else ""
    if table not in ("facets", "files"):
        raise SystemExit("usage: python -m docs.geometry.files facets|files")
    with tempfile.TemporaryDirectory() as folder:
        (facets if table == "facets" else files)(Path(folder))


if __name__ == "__main__":
    main()
