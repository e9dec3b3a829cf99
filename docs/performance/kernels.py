"""The numpy and the compiled kernel on every shipped scene: integration time and agreement.

Usage (from the repository root; about a minute once the meshes are cached)::

    .venv/bin/python -m docs.performance.kernels [--repeats 3]

For each scene of ``cases/*.toml`` at its shipped numerics: the integration time of one run in
process with ``numerics.kernel = "numpy"`` and ``"compiled"`` (the minimum of ``--repeats``, after
a first run that prepares the projectile and loads the compiled code), their ratio, the steps and
load evaluations of each, and the relative difference of depth and path length between the two,
as its power of ten, marked ``~`` (the two sum in another order, so the last bits differ from one
machine to the next; docs/numerics.md, "The compiled step").
"""

from __future__ import annotations

import argparse
import math
import sys

from cases import SHIPPED_SCENES, load_scene, run_scene, scene_path
from docs.measure import stamp


def _below(difference: float) -> str:
    """``~1e-k`` (docs/regenerate.py: round-off, not compared), the power of ten nearest ``difference``."""
    return "0" if difference == 0.0 else f"~1e{round(math.log10(difference)):d}"


def _timed(name: str, kernel: str, repeats: int):
    scene = load_scene(scene_path(name), {"numerics.kernel": kernel})
    run_scene(scene)
    results = [run_scene(scene) for _ in range(repeats)]
    return min(r.integration_time for r in results), results[-1].trajectory


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    print(
        "| scene | numpy | compiled | ratio | steps (numpy / compiled) | load evaluations | depth difference |"
        " path difference |"
    )
    print("|---|---|---|---|---|---|---|---|")
    for name in SHIPPED_SCENES:
        (slow, a), (fast, b) = (_timed(name, kernel, args.repeats) for kernel in ("numpy", "compiled"))
        depth_a, depth_b = abs(a.position[-1][2]), abs(b.position[-1][2])
        path_a, path_b = a.path_length[-1], b.path_length[-1]
        print(
            f"| {name} | {slow:.3f} s | {fast:.3f} s | {slow / fast:.1f}x | {a.statistics['steps']} /"
            f" {b.statistics['steps']} | {a.statistics['load_evaluations']} / {b.statistics['load_evaluations']} |"
            f" {_below(abs(depth_a - depth_b) / depth_a)} | {_below(abs(path_a - path_b) / path_a)} |",
            flush=True,
        )
    print()
    print(stamp())
    return 0


if __name__ == "__main__":
    sys.exit(main())
