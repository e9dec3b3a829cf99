"""Surface the target cannot reach (docs/evidence-geometry.md, "Exposure"): what it changes and what it costs.

Run from the repository root: ``python -m docs.geometry.exposure`` (about a minute).  It writes three bodies
with gmsh's own primitives (docs/geometry/cad_bodies.py): a 105 mm, 600 mm steel body with a CRH 2.5 ogive,
the same with a flat base recess (20 mm deep, 35 mm radius), and the same with a ring groove around the
shank (10 mm wide, 10 mm deep, 300 mm from the tail); it runs each at 400 m/s and 5 degrees of attack in
test 2's soil, with exposure on and off, against the plain body given the changed body's own mass
properties (so that only the surface differs); then it times the compiled load of the shipped finned body
with exposure on and off (medians of alternating runs).
"""

from __future__ import annotations

import math
import tempfile
import time
from pathlib import Path

import numpy as np

from cases import load_scene, run_scene, scene_path, summarise
from cases.run import prepare_projectile
from cases.run.compiled import compiled_modules
from cases.scene.projectile import MassPropertiesSpec
from docs.geometry.cad_bodies import write_changed_body
from docs.measure import stamp
from dynamics.quaternion import rotation_matrix

SHOT = {"impact.speed": 400.0, "impact.attack_angle": 5.0}
CHANGES = {
    "base recess, 20 mm deep, 35 mm radius": {"recess": (0.02, 0.035)},
    "shank groove, 10 mm wide, 10 mm deep": {"groove": (0.3, 0.01, 0.01)},
}


def _scene(path: Path, **projectile):
    spec = {"geometry": {"file": str(path), "unit": "mm"}, **projectile}
    return load_scene(scene_path("forrestal_luk_test2"), {"projectile": spec, **SHOT})


def shots(folder: Path) -> None:
    """The table of depths and turns."""
    plain = write_changed_body(folder / "plain.step")
    print("| body | exposure | depth (m) | against the plain body | axis turn (deg) | against the plain body |")
    print("|---|---|---|---|---|---|")
    for label, change in CHANGES.items():
        path = write_changed_body(folder / f"{label.split(',')[0].replace(' ', '_')}.step", **change)
        changed = _scene(path, body_density=7850.0)
        given = MassPropertiesSpec.of(prepare_projectile(changed).mass).model_dump()
        reference = summarise(run_scene(_scene(plain, mass_properties=given)))
        for exposure in (True, False):
            scene = load_scene(
                scene_path("forrestal_luk_test2"),
                {"projectile": {"geometry": {"file": str(path), "unit": "mm"}, "body_density": 7850.0}, **SHOT,
                 "effects.exposure": exposure},
            )  # fmt: skip
            run = summarise(run_scene(scene))
            depth, turn = run.depth / reference.depth - 1.0, run.axis_angle_change - reference.axis_angle_change
            print(
                f"| {label} | {'on' if exposure else 'off'} | {run.depth:.4f} | {depth:+.1e} |"
                f" {run.axis_angle_change:.3f} | {turn:+.3f} |"
            )
        print(f"| (plain body, the changed body's mass properties) | | {reference.depth:.4f} | | "
              f"{reference.axis_angle_change:.3f} | |")  # fmt: skip


def cost() -> None:
    """Median time of one compiled load evaluation of the shipped finned body, exposure off and on."""
    _, layout = compiled_modules()
    scene = load_scene(scene_path("finned_test2"))
    quadrature = prepare_projectile(scene).quadrature
    data = {
        flag: layout.kernel_data(load_scene(scene_path("finned_test2"), {"effects.exposure": flag}).loads(quadrature))
        for flag in (False, True)
    }
    nose_down = rotation_matrix(np.array([math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0]))
    out = np.empty(6)
    print()
    print("| attack angle (deg) | exposure off | exposure on | ratio |")
    print("|---|---|---|---|")
    for attack in (0.0, 5.0, 30.0):
        a = math.radians(attack)
        state = (
            np.array([0.0, 0.0, -3.0]),
            nose_down @ (300.0 * np.array([math.cos(a), 0.0, -math.sin(a)])),
            nose_down,
            np.array([0.0, 0.5, 0.0]),
        )
        times: dict[bool, list[float]] = {False: [], True: []}
        for _ in range(9):  # alternating
            for flag in (False, True):
                start = time.perf_counter()
                for _ in range(2000):
                    layout.dafl_kernel(data[flag], *state, out)
                times[flag].append((time.perf_counter() - start) / 2000 * 1e6)
        off, on = float(np.median(times[False])), float(np.median(times[True]))
        print(f"| {attack:g} | {off:.1f} us | {on:.1f} us | {on / off:.2f}x |")
    print()
    print(stamp())


def main() -> None:
    with tempfile.TemporaryDirectory() as folder:
        shots(Path(folder))
    cost()


if __name__ == "__main__":
    main()
