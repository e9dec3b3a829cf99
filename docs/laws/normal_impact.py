"""Test 2 on a 10 mm mesh under each law family, a user's law and both contact ramps, against the 1-D integration
of the same law over the exact profile: the table of docs/evidence-laws.md.  Run from the repository root::

    python -m docs.laws.normal_impact
"""

from __future__ import annotations

from cases import history_table, load_scene, run_scene, scene_path
from cases.reference.normal_impact import scene_depth_1d
from docs.measure import stamp

LAWS = {
    "cavity expansion (soil)": "soil",
    "polynomial": {"model": "polynomial", "c0": 1.2e7, "c1": 3e4, "c2": 1500.0},
    "power": {"model": "power", "c0": 1.5e7, "c": 2e4, "n": 1.6},
    "cavity expansion, k = 3 MPa/m": {"A": 1.718, "sigma_0": 10e6, "B": 1.227, "rho_0": 1860.0, "depth_gradient": 3e6},
    "user: rate_hardening": {
        "function": str(scene_path("paper_p3").parent / "laws" / "soil_laws.py") + ":rate_hardening",
        "parameters": {"c0": 1.2e7, "c2": 2000.0, "reference_speed": 300.0, "exponent": 0.5},
    },
}


def main() -> None:
    print("| law | contact | depth, 10 mm mesh (m) | 1-D integration (m) | difference |")
    print("|---|---|---|---|---|")
    for label, law in LAWS.items():
        for contact in ("one_sided", "centred"):
            overrides = {"target.law": law, "effects.contact": contact, "numerics.mesh_size": 0.01}
            scene = load_scene(scene_path("forrestal_luk_test2"), {**overrides, "numerics.kernel": "compiled"})
            result = run_scene(scene)
            depth = float(history_table(result)["tip_depth"].max())
            prepared = result.prepared
            reference = scene_depth_1d(scene, prepared)
            print(f"| {label} | {contact} | {depth:.5f} | {reference:.5f} | {100 * (depth / reference - 1):+.3f} % |")
    print()
    print(stamp())


if __name__ == "__main__":
    main()
