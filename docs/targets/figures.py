"""The pictures of docs/targets.md: the inclination convention and three off-screen renders of shipped scenes.

Run: ``.venv/bin/python -m docs.targets.figures`` (about 40 s).  Writes ``docs/targets/inclination.png`` (the
convention: a level target hit obliquely and the same shot into an inclined target hit vertically) and, for three
shipped scenes, the field at the largest load with the path beside it (``concrete_slab.png``,
``soil_over_sloping_concrete.png``, ``spaced_plates.png``), and prints each run's end.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from matplotlib.axes import Axes

from cases import load_scene, scene_path
from cases.run import run_scene, summarise
from cases.scene import Target
from cases.viz import FieldEvaluator, save_figure, subplots
from cases.viz.frames import render_snapshots
from cases.viz.target_view import target_view
from docs.measure import stamp

HERE = Path(__file__).parent
RENDERED = ("concrete_slab", "soil_over_sloping_concrete", "spaced_plates")


def _panel(ax: Axes, target: Target, oblique: float, title: str) -> None:
    view = target_view(target, (-1.5, 1.5, -1.6, 0.8))
    for band, shade in zip(view.bands, view.shades):
        ax.fill(band[:, 0], band[:, 1], color=shade, lw=0)
    for face in view.faces:
        ax.plot(face[:, 0], face[:, 1], color="saddlebrown", lw=1.5)
    angle = math.radians(target.inclination)
    normal = np.array([math.sin(angle), math.cos(angle)])
    ax.annotate("", xy=(0.7 * normal[0], 0.7 * normal[1]), xytext=(0, 0), arrowprops={"arrowstyle": "->"})
    ax.text(0.78 * normal[0], 0.78 * normal[1], "n", fontsize=10)
    beta = math.radians(oblique)
    start = (-0.7 * math.sin(beta), 0.7 * math.cos(beta))
    ax.annotate("", xy=(0, 0), xytext=start, arrowprops={"arrowstyle": "->", "color": "crimson", "lw": 2})
    ax.text(start[0] - 0.05, start[1] + 0.05, "velocity", color="crimson", fontsize=9, ha="right")
    ax.set(xlim=(-1.5, 1.5), ylim=(-1.6, 0.8), xlabel="X (m)", ylabel="Z (m)", aspect="equal", title=title)


def convention() -> None:
    layers = [{"thickness": 0.6, "law": "soil"}, {"law": "soil"}]
    fig, (left, right) = subplots(1, 2, figsize=(9.0, 3.8))
    _panel(left, Target.model_validate({"layers": layers}), 30.0, "level, oblique_angle = 30 deg")
    _panel(right, Target.model_validate({"layers": layers, "inclination": 30.0}), 0.0, "inclination = 30 deg, vertical")
    fig.tight_layout()
    save_figure(fig, HERE / "inclination.png")


def renders() -> None:
    for name in RENDERED:
        result = run_scene(load_scene(scene_path(name)))
        summary = summarise(result)
        evaluator = FieldEvaluator(result)
        # the field at the largest load (the nose inside a layer), with the path and the target beside it
        loaded = int(np.argmax(np.linalg.norm(result.trajectory.force, axis=1)))
        (written,) = render_snapshots(evaluator, HERE, [(name, loaded)])
        written.replace(HERE / f"{name}.png")
        residual = (
            f", residual velocity {summary.residual_velocity:.1f} m/s" if summary.end_reason == "perforated" else ""
        )
        print(f"- `{name}`: {summary.end_reason} at {summary.final_time * 1e3:.2f} ms{residual}")


if __name__ == "__main__":
    convention()
    renders()
    print()
    print(stamp())  # the step counts behind the pictures hang on the processor
