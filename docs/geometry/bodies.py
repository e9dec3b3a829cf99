"""The shipped non-axisymmetric bodies run as shipped (docs/evidence-geometry.md).

Run from the repository root: ``python -m docs.geometry.bodies`` (a few seconds once the meshes are
cached).  Prints a markdown table: for ``cases/eroded_test2.toml`` and ``cases/finned_test2.toml``
beside the axisymmetric ``cases/forrestal_luk_test2.toml``, the mesh's volume and transverse
inertia against OpenCASCADE's integrals over the CAD solid, and the run: tip depth, path length,
the largest attack angle, the axis turn and the lateral drift of the centre of mass.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from cases import load_scene, run_scene, summarise
from docs.geometry.cad_bodies import occ_mass_properties

ROOT = Path(__file__).resolve().parents[2]
SCENES = {
    "forrestal_luk_test2": None,
    "eroded_test2": "cases/bodies/eroded_test2.step",
    "finned_test2": "cases/bodies/finned_test2.step",
}


def main() -> None:
    print(
        "| scene | volume: mesh / CAD - 1 | transverse inertia I_yy: mesh / CAD - 1 | tip depth (m) | "
        "path length (m) | largest attack angle (deg) | axis turn (deg) | drift sideways (mm) |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name, step in SCENES.items():
        result = run_scene(load_scene(ROOT / "cases" / f"{name}.toml"))
        summary = summarise(result)
        mass = result.prepared.mass
        if step is None:
            volume_error = inertia_error = "- (analytic)"
        else:
            volume, _, inertia = occ_mass_properties(ROOT / step, scale=1e-3)  # a STEP file in mm
            volume_error = f"{mass.volume / volume - 1:+.1e}"
            inertia_error = f"{(mass.inertia[1, 1] / mass.mass) / (inertia[1, 1] / volume) - 1:+.1e}"
        drift = float(np.hypot(*result.trajectory.position[-1, :2])) * 1e3
        print(
            f"| `{name}` | {volume_error} | {inertia_error} | {summary.depth:.3f} | {summary.path_length:.3f} | "
            f"{summary.max_attack_angle:.3f} | {summary.axis_angle_change:+.3f} | {drift:.1f} |"
        )


if __name__ == "__main__":
    main()
