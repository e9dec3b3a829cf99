"""One DAFL load evaluation of #3: the numpy path, the compiled kernel and a compiled lower bound.

Usage (from the repository root; about a minute once the meshes are cached, three from an empty cache)::

    .venv/bin/python -m docs.performance.loads

The state and the three measurements are the benchmark's (``./dev bench -k load_evaluation``,
tests/benchmarks/test_performance.py), from docs/performance/lower_bound.py, which both share: #3 at
800 m/s with a 1-degree attack angle and a pitch rate, wholly embedded or with the nose entering; the
numpy load as a run calls it; the compiled kernel called 100 times from compiled code (as inside a
compiled step); and the lower bound, a plain C loop over every point with the same smooth steps, built
with ``cc -O3 -march=native`` and the licence the compiled kernel has (reassociation, fused
multiply-adds).  Medians of 15 samples, microseconds per evaluation.  Prints a markdown table and the
stamp line.
"""

from __future__ import annotations

import statistics
import tempfile
import timeit
from pathlib import Path

from cases import load_scene, prepare_projectile, scene_path
from docs.measure import stamp
from docs.performance.lower_bound import benchmark_state, c_loop_call, compiled_call, median_per_call

MESHES = (0.04, 0.02, 0.01, 0.005)


def measure(mesh_size: float, depth: float, folder: Path) -> tuple[int, float, float, float]:
    """Points, and numpy, compiled and C-loop microseconds per evaluation at ``depth`` (m)."""
    scene = load_scene(scene_path("paper_p3"), {"numerics.mesh_size": mesh_size})
    loads = scene.loads(prepare_projectile(scene).quadrature)
    position, velocity, rotation, spin = benchmark_state(depth)
    numpy = (
        statistics.median(timeit.repeat(lambda: loads(position, velocity, rotation, spin), number=100, repeat=15)) / 100
    )
    compiled = median_per_call(compiled_call(loads, position, velocity, rotation, spin))
    c_loop = median_per_call(c_loop_call(loads, position, velocity, rotation, spin, folder))
    return len(loads), numpy * 1e6, compiled * 1e6, c_loop * 1e6


def main() -> None:
    print("| mesh | surface points | numpy, embedded / entering | compiled | C loop | compiled / C loop |")
    print("|---|---|---|---|---|---|")
    with tempfile.TemporaryDirectory() as folder:
        for size in MESHES:
            rows = [measure(size, depth, Path(folder)) for depth in (-3.0, -0.3)]
            (n, *embedded), (_, *entering) = rows
            pairs = [f"{a:.1f} us / {b:.1f} us" for a, b in zip(embedded, entering)]
            ratio = f"{embedded[1] / embedded[2]:.2f}x / {entering[1] / entering[2]:.2f}x"
            print(
                f"| {1e3 * size:g} mm | {format(n, ',').replace(',', ' ')} | {' | '.join(pairs)} | {ratio} |",
                flush=True,
            )
    print()
    print(stamp())


if __name__ == "__main__":
    main()
