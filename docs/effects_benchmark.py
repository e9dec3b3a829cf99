"""Measure what each optional effect costs (docs/evidence-effects.md).

Run: ``.venv/bin/python -m docs.effects_benchmark`` (about a minute).  Prints, for the
shipped test 5 scene (Forrestal-Luk projectile, 20 mm mesh, 14 160 surface points):

* the median time of one load evaluation (15 repeats of 200 calls) at a state
  with the nose and 1 m of shank in the target, 3 degrees of attack and a pitch rate;
* the integration time of test 5 (median of 3 runs), its steps and path length.
"""

from __future__ import annotations

import statistics
import timeit

import numpy as np

from cases import load_scene, prepare_projectile, run_scene, scene_path
from cases.run import initial_state, summarise
from cases.run.runner import WithGravity
from cases.scene import parse_override
from docs.measure import stamp
from dynamics.quaternion import rotation_matrix
from fem_loads import DAFLLoads

EFFECTS = {
    "all effects off (scene defaults)": [],
    "Coulomb friction": ["effects.friction.model=coulomb"],
    "capped friction": ['effects.friction={model = "capped", coefficient = 0.1, cap = 10e6}'],
    "free surface": ["effects.free_surface.depth=0.5"],
    "no separation": ["effects.separation=false"],
    "gravity": ["effects.gravity=true"],
}


def load_timing(loads, args) -> float:
    times = timeit.repeat(lambda: loads(*args), number=200, repeat=15)
    return statistics.median(times) / 200 * 1e6


def main() -> None:
    scene = load_scene(scene_path("forrestal_luk_test5"))
    prepared = prepare_projectile(scene)
    state = initial_state(scene, prepared)
    rotation = rotation_matrix(state.attitude)
    position = state.position + np.array([0.0, 0.0, -(0.16 + 1.0)])
    args = (position, state.velocity, rotation, np.array([0.0, 2.0, 0.0]))
    sharp = DAFLLoads(prepared.quadrature, scene.target.build())
    bare = DAFLLoads(
        prepared.quadrature,
        scene.target.build(),
        **scene.effects.contact_ramp,
        entry_smoothing=scene.numerics.entry_smoothing,
    )
    bare_us = load_timing(bare, args)
    print(
        "| configuration | one load evaluation (us, median) | against the bare core | "
        "test 5 integration (s, median of 3) | steps | path length (m) |"
    )
    print("|---|---|---|---|---|---|")
    sharp_us = load_timing(sharp, args)
    print(
        f"| sharp core (DAFLLoads with the law only: the paper's switches) | {sharp_us:.0f} us | "
        f"{sharp_us / bare_us:.2f}x | - | - | - |"
    )
    print(f"| bare core (the law and the default contact and entry ramps) | {bare_us:.0f} us | 1.00x | - | - | - |")
    rows = [
        (name, load_scene(scene_path("forrestal_luk_test5"), [parse_override(text) for text in overrides]))
        for name, overrides in EFFECTS.items()
    ]
    rows.append(
        (
            "two layers",
            load_scene(
                scene_path("forrestal_luk_test5"),
                {"target.layers": [{"thickness": 2.0, "law": "soil"}, {"law": "softer_soil"}]},
            ),
        )
    )
    for name, s in rows:
        loads = s.loads(prepared.quadrature)
        if s.effects.gravity:
            loads = WithGravity(loads, prepared.mass.mass, s.effects.gravity_acceleration)
        per_call = load_timing(loads, args)
        results = [run_scene(s) for _ in range(3)]
        result = summarise(results[0])
        print(
            f"| {name} | {per_call:.0f} us | {per_call / bare_us:.2f}x | "
            f"{statistics.median(r.integration_time for r in results):.2f} s | {result.steps} | "
            f"{result.path_length:.2f} |"
        )
    print()
    print(stamp())


if __name__ == "__main__":
    main()
