"""The numpy and the compiled kernel on every shipped scene and every law family: integration time and agreement.

Usage (from the repository root; about two minutes once the meshes are cached)::

    .venv/bin/python -m docs.performance.kernels [--repeats 3]

For each scene of ``cases/*.toml`` at its shipped numerics, and for test 2 under each law family and
target of :data:`FAMILIES`: the integration time of one run in process with ``numerics.kernel =
"numpy"`` and ``"compiled"`` (the minimum of ``--repeats``, alternating, after a first run of each that
prepares the projectile and loads the compiled code), their ratio, the kernel ``auto`` picks for a
study, the steps and load evaluations of each, and the relative difference of depth and path length
between the two, as its power of ten, marked ``~`` (the two sum in another order, so the last bits
differ from one machine to the next; docs/numerics.md, "The compiled step").
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

from cases import SHIPPED_SCENES, load_scene, run_scene, scene_path
from docs.measure import stamp

_USER_LAW = Path(__file__).resolve().parents[2] / "cases" / "laws" / "soil_laws.py"
#: test 2 under each law family and target: the overrides of its scene file
FAMILIES = {
    "test 2, friction": {"effects.friction": {"model": "coulomb", "coefficient": 0.1}},
    "test 2, depth gradient": {
        "target.law": {
            "model": "cavity_expansion",
            "A": 1.718,
            "B": 1.227,
            "sigma_0": 10e6,
            "rho_0": 1860.0,
            "depth_gradient": 1e6,
        }
    },
    "test 2, two layers": {
        "target.layers": [{"thickness": 2.0, "law": "soil"}, {"law": {"model": "polynomial", "c0": 10e6, "c2": 2000.0}}]
    },
    "test 2, concrete family": {"target.law": {"model": "concrete", "compressive_strength": 35e6, "density": 2300.0}},
    "test 2, power law": {"target.law": {"model": "power", "c0": 17.18e6, "c": 5000.0, "n": 1.9}},
    "test 2, strength table": {
        "target.law": {
            "model": "polynomial",
            "c0": 17.18e6,
            "c2": 2282.2,
            "strength_table": [[0.0, 0.0], [2.0, 1e6], [5.0, 3e6]],
        }
    },
    "test 2, user law": {
        "target.law": {
            "function": f"{_USER_LAW}:rate_hardening",
            "parameters": {"c0": 17.18e6, "c2": 2282.2, "reference_speed": 300.0, "exponent": 0.5},
        }
    },
}


def _below(difference: float) -> str:
    """``~1e-k`` (docs/regenerate.py: round-off, not compared), the power of ten nearest ``difference``."""
    return "0" if difference == 0.0 else f"~1e{round(math.log10(difference)):d}"


def timed(name: str, overrides: dict, repeats: int) -> dict:
    """Integration times (s, the minimum of ``repeats``, alternating kernels after a first run of each), last
    trajectories and ``auto``'s pick in a study, of scene ``name`` with ``overrides``."""
    scenes = {kernel: load_scene(scene_path(name), {**overrides, "numerics.kernel": kernel}) for kernel in KERNELS}
    for scene in scenes.values():
        run_scene(scene)
    times: dict[str, list[float]] = {kernel: [] for kernel in KERNELS}
    trajectories = {}
    for _ in range(repeats):
        for kernel, scene in scenes.items():
            result = run_scene(scene)
            times[kernel].append(result.integration_time)
            trajectories[kernel] = result.trajectory
    auto = load_scene(scene_path(name), overrides).with_kernel(many_runs=True).numerics.kernel
    return {"time": {k: min(t) for k, t in times.items()}, "trajectory": trajectories, "auto": auto}


KERNELS = ("numpy", "compiled")


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args(argv)
    print(
        "| scene | numpy | compiled | ratio | auto | steps (numpy / compiled) | load evaluations | depth difference |"
        " path difference |"
    )
    print("|---|---|---|---|---|---|---|---|---|")
    cases = [(name, name, {}) for name in SHIPPED_SCENES]
    cases += [(label, "forrestal_luk_test2", overrides) for label, overrides in FAMILIES.items()]
    for label, name, overrides in cases:
        measured = timed(name, overrides, args.repeats)
        slow, fast = (measured["time"][kernel] for kernel in KERNELS)
        a, b = (measured["trajectory"][kernel] for kernel in KERNELS)
        depth_a, depth_b = abs(a.position[-1][2]), abs(b.position[-1][2])
        path_a, path_b = a.path_length[-1], b.path_length[-1]
        print(
            f"| {label} | {slow:.3f} s | {fast:.3f} s | {slow / fast:.1f}x | {measured['auto']} |"
            f" {a.statistics['steps']} / {b.statistics['steps']} |"
            f" {a.statistics['load_evaluations']} / {b.statistics['load_evaluations']} |"
            f" {_below(abs(depth_a - depth_b) / depth_a)} | {_below(abs(path_a - path_b) / path_a)} |",
            flush=True,
        )
    print()
    print(stamp())
    return 0


if __name__ == "__main__":
    sys.exit(main())
