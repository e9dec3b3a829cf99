"""The independent checks of docs/evidence-targets.md: slabs, gaps, inclined faces and the ballistic limit.

Run: ``.venv/bin/python -m docs.targets.checks`` (about 40 s).  Every full run is test 2's projectile (Forrestal
and Luk: 23.1 kg, 95.2 mm, CRH 3) with its soil law at 280 m/s, no free-surface reduction, no friction, the
shipped numerics; each is set beside an independent figure: a 1-D integration of the nose through the target's
slices (exact profile, no mesh), the same run through another target that must give the same answer, or the
same scene turned about Y.
"""

from __future__ import annotations

import json
import tempfile
from pathlib import Path

from cases import scene_path
from cases.reference.normal_impact import scene_slab_1d
from cases.run import prepare_projectile, run_scene, summarise
from cases.scene import Scene
from cases.scene.load import read_scene_data, scene_from_dict
from docs.measure import penetrate_output, stamp

SOIL = "soil"
STATIC = {"model": "polynomial", "c0": 17.18e6}  # rate independent: the same work through the same thickness


def shot(target: dict, **impact: float) -> Scene:
    data = read_scene_data(scene_path("forrestal_luk_test2"))
    data["target"], data["numerics"]["kernel"] = target, "compiled"
    data["impact"].update(impact)
    return scene_from_dict(data, "test 2")


def slab(*layers: tuple[float, object]) -> dict:
    return {"layers": [{"thickness": t, "law": law} for t, law in layers]}


def one_d(scene: Scene) -> float:
    return scene_slab_1d(scene, prepare_projectile(scene))[0]


def main() -> None:
    print("| check | target | full model | independent figure | difference |")
    print("|---|---|---|---|---|")
    rows = {}
    for name, target in (
        ("2 m slab", slab((2.0, SOIL))),
        ("1 m + 0.5 m gap + 1 m", slab((1.0, SOIL), (0.5, "air"), (1.0, SOIL))),
        ("2 m slab, rate-independent law", slab((2.0, STATIC))),
        ("1 m + 0.5 m gap + 1 m, rate-independent law", slab((1.0, STATIC), (0.5, "air"), (1.0, STATIC))),
    ):
        scene = shot(target)
        summary = summarise(run_scene(scene))
        rows[name] = summary.residual_velocity
        reference = one_d(scene)
        difference = summary.residual_velocity / reference - 1
        print(
            f"| residual velocity against the 1-D nose | {name} | {summary.residual_velocity:.3f} m/s"
            f" ({summary.end_reason}, {summary.steps} steps) | {reference:.3f} m/s | {difference:+.2e} |"
        )
    for soil, gapped in (
        ("2 m slab", "1 m + 0.5 m gap + 1 m"),
        ("2 m slab, rate-independent law", "1 m + 0.5 m gap + 1 m, rate-independent law"),
    ):
        print(
            f"| the gap against the slab (full model both) | {gapped} | {rows[gapped]:.3f} m/s | {rows[soil]:.3f} m/s"
            f" | {rows[gapped] / rows[soil] - 1:+.2e} |"
        )
    level = summarise(run_scene(shot({"law": SOIL}, oblique_angle=30.0)))
    inclined = summarise(run_scene(shot({"law": SOIL, "inclination": 30.0})))
    path, turn = inclined.path_length / level.path_length - 1, inclined.axis_angle_change - level.axis_angle_change
    print(
        "| path length: inclined 30 deg, hit vertically, against level, hit 30 deg oblique | half-space |"
        f" {inclined.path_length:.6f} m | {level.path_length:.6f} m | {path:+.2e} |"
    )
    print(
        f"| axis turn, the same pair | half-space | {inclined.axis_angle_change:.5f} deg |"
        f" {level.axis_angle_change:.5f} deg | {turn:+.1e} deg |"
    )
    with tempfile.TemporaryDirectory() as folder:
        text = scene_path("forrestal_luk_test2").read_text()
        head, rest = text.split("[target]\n", 1)
        scene_file = Path(folder) / "slab.toml"
        scene_file.write_text(
            head + '[target]\nlayers = [{ thickness = 2.0, law = "soil" }]\n' + rest[rest.index("\n[impact]") :]
        )
        arguments = ["ballistic-limit", str(scene_file), "--store", str(Path(folder) / "store"), "--json"]
        limit = json.loads(penetrate_output([*arguments, "--no-progress"]))
    predicted, (low, high) = limit["predicted_limit"], limit["bracket"]
    runs = {run["speed"]: run["end_reason"] for run in limit["runs"]}
    # the bracket comes from full runs: the full model's limit lies in it, whatever guided the first runs there
    print(
        f"| `penetrate ballistic-limit` against the 1-D model's limit | 2 m slab | between {low:g} ({runs[low]}) and"
        f" {high:g} m/s ({runs[high]}), {limit['full_runs']} full runs | {predicted:.3f} m/s | within"
        f" {max(predicted - low, high - predicted) / predicted:.2%} |"
    )
    print()
    print(stamp())  # the differences at round-off (the turned scene) hang on the processor


if __name__ == "__main__":
    main()
