"""Measure what rendering costs (docs/evidence-rendering.md).

Run: ``.venv/bin/python -m docs.rendering.benchmark`` (about a minute and a half on 2 cores).
Projectile #3 at 1120 m/s with the shipped numerics (10 mm mesh, RK4 at 10 us).  Prints:

* the run and the set-up of the field evaluator (mesh from the cache, loads);
* one frame at 1280 x 640 (the ``penetrate render`` snapshot size), and the parts of it spent
  in the field evaluation and the matplotlib side panel (the rest is the 3-D view: render and
  read-back): medians of 50 frames after 5 warm-up frames;
* the resident memory before and after those 50 frames (``/proc/self/statm``);
* the four snapshots, the trajectory view, the 60-frame GIF at 960 x 480 and 100 ParaView steps
  (wall time and bytes).
"""

from __future__ import annotations

import gc
import statistics
import tempfile
import time
from pathlib import Path

import numpy as np

from cases import load_scene, run_scene, scene_path
from cases.viz.field import FieldEvaluator, resolve_instants
from cases.viz.frames import FrameRenderer, render_animation, render_snapshots
from cases.viz.paraview import write_paraview
from cases.viz.trajectory import render_trajectory
from docs.measure import stamp


def rss_bytes() -> int:
    """Resident memory of this process (bytes), from ``/proc/self/statm`` (Linux)."""
    import os

    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def main() -> None:
    scene = load_scene(scene_path("paper_p3"), {"impact.speed": 1120})
    start = time.perf_counter()
    result = run_scene(scene)
    run_seconds = time.perf_counter() - start
    start = time.perf_counter()
    evaluator = FieldEvaluator(result)
    setup_seconds = time.perf_counter() - start
    rows_out = [
        (
            "the run and the field evaluator",
            f"{run_seconds:.1f} s and {setup_seconds:.2f} s "
            f"({len(evaluator)} recorded steps, {evaluator.surface.n_facets} facets drawn as "
            f"{len(evaluator.surface.triangles)} triangles)",
        )
    ]

    rows = np.linspace(0, len(evaluator) - 1, 55).astype(int)
    timings: dict[str, list[float]] = {"whole frame": [], "field evaluation": [], "side panel": []}
    with FrameRenderer(evaluator, (1280, 640)) as renderer:
        for row in rows[:5]:
            renderer.render(int(row))
        gc.collect()
        before = rss_bytes()
        for row in rows[5:]:
            t0 = time.perf_counter()
            renderer.render(int(row))
            t1 = time.perf_counter()
            evaluator.at(int(row))
            t2 = time.perf_counter()
            renderer.panel.draw(int(row))
            t3 = time.perf_counter()
            timings["whole frame"].append(t1 - t0)
            timings["field evaluation"].append(t2 - t1)
            timings["side panel"].append(t3 - t2)
        gc.collect()
        after = rss_bytes()
    medians = {name: statistics.median(values) for name, values in timings.items()}
    medians["3-D view (the rest)"] = medians["whole frame"] - medians["field evaluation"] - medians["side panel"]
    rows_out.append(
        (
            "one field image, 1280x640 (median of 50 frames)",
            ", ".join(f"{name} {value * 1e3:.0f} ms" for name, value in medians.items()),
        )
    )
    rows_out.append(
        ("resident memory over those 50 frames", f"{before / 1e6:.0f} MB before, {after / 1e6:.0f} MB after")
    )

    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        instants = resolve_instants(evaluator, None)
        t0 = time.perf_counter()
        paths = render_snapshots(evaluator, out, instants)
        t1 = time.perf_counter()
        render_trajectory(evaluator, out / "trajectory.png")
        t2 = time.perf_counter()
        movie = render_animation(evaluator, out / "animation.gif", frames=60)
        t3 = time.perf_counter()
        written = write_paraview(evaluator, out / "paraview", steps=100)
        t4 = time.perf_counter()
        size = sum(p.stat().st_size for p in (out / "paraview").rglob("*") if p.is_file())
        rows_out += [
            (
                f"the {len(paths)} field images",
                f"{t1 - t0:.1f} s ({sum(p.stat().st_size for p in paths) / 1e3:.0f} kB)",
            ),
            ("the trajectory view", f"{t2 - t1:.1f} s"),
            (
                f"the animation, {movie['frames']} frames at 960x480",
                f"{t3 - t2:.1f} s ({movie['seconds_per_frame']:.2f} s a frame, {movie['bytes'] / 1e6:.1f} MB)",
            ),
            (f"ParaView, {len(written['surfaces'])} steps", f"{t4 - t3:.1f} s ({size / 1e6:.0f} MB)"),
        ]
    print("| what | measured |")
    print("|---|---|")
    for what, measured in rows_out:
        print(f"| {what} | {measured} |")
    print()
    print(stamp())


if __name__ == "__main__":
    main()
