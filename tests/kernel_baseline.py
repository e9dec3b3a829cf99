"""The results a change of the load kernel's structure must keep: every shipped scene on both kernels.

Usage (from the repository root)::

    .venv/bin/python tests/kernel_baseline.py record     # writes tests/kernel_baseline.csv
    .venv/bin/python tests/kernel_baseline.py check      # runs them again and prints the differences

``record`` runs every shipped scene (``cases/*.toml``) as shipped, once with ``numerics.kernel = "numpy"``
and once with ``"compiled"`` (where the compiled kernel covers the scene), and writes its depth, path length
and axis turn with every digit.  The committed table is the baseline that ``tests/fem_loads/test_kernel_baseline.py``
(a slow test) holds the code to:

* a straight scene (its axis turns less than 1e-6 degrees) within 1e-9 of its depth and path length;
* a turning scene within 1e-5 of its path length (relative) and 1e-3 degrees of its turn, and its depth
  within 1e-5 too.

A turning run amplifies round-off (a reordered sum moves its last digits, and the turn grows them), which is
why it is held to less.  Record again only for a change that is meant to change results, and say so.
"""

from __future__ import annotations

import csv
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TABLE = Path(__file__).resolve().with_name("kernel_baseline.csv")
FIELDS = ("scene", "kernel", "depth", "path_length", "axis_angle_change", "end_reason")
KERNELS = ("numpy", "compiled")
#: the axis turn (degrees) under which a scene counts as straight
STRAIGHT_TURN = 1e-6
STRAIGHT_TOLERANCE = 1e-9
TURNING_TOLERANCE = 1e-5
TURNING_TURN_TOLERANCE = 1e-3


def cases() -> list[tuple[str, str]]:
    """``(scene, kernel)`` of every shipped scene on each kernel that covers it."""
    from cases import SHIPPED_SCENES, load_scene, scene_path

    found = []
    for name in SHIPPED_SCENES:
        scene = load_scene(scene_path(name))
        found += [(name, kernel) for kernel in KERNELS if kernel == "numpy" or scene.compilable]
    return found


def run(name: str, kernel: str) -> dict[str, str]:
    """One row of the table: the scene as shipped, on ``kernel``."""
    from cases import load_scene, run_scene, scene_path, summarise

    summary = summarise(run_scene(load_scene(scene_path(name), {"numerics.kernel": kernel})))
    return {
        "scene": name,
        "kernel": kernel,
        "depth": repr(float(summary.depth)),
        "path_length": repr(float(summary.path_length)),
        "axis_angle_change": repr(float(summary.axis_angle_change)),
        "end_reason": summary.end_reason,
    }


def read() -> list[dict[str, str]]:
    """The committed baseline."""
    with TABLE.open() as file:
        return list(csv.DictReader(line for line in file if not line.startswith("#")))


def differences(want: dict[str, str], got: dict[str, str]) -> list[str]:
    """What moved beyond the tolerances (module docstring), one line each; empty when nothing did."""
    straight = abs(float(want["axis_angle_change"])) < STRAIGHT_TURN
    tolerance = STRAIGHT_TOLERANCE if straight else TURNING_TOLERANCE
    found = []
    for key in ("depth", "path_length"):
        a, b = float(want[key]), float(got[key])
        if abs(b - a) > tolerance * abs(a):
            found.append(f"{key} {b!r} against {a!r} ({b / a - 1:+.2e}; allowed {tolerance:g})")
    turn_tolerance = STRAIGHT_TURN if straight else TURNING_TURN_TOLERANCE
    a, b = float(want["axis_angle_change"]), float(got["axis_angle_change"])
    if abs(b - a) > turn_tolerance:
        found.append(f"axis_angle_change {b!r} against {a!r} deg (allowed {turn_tolerance:g} deg)")
    if got["end_reason"] != want["end_reason"]:
        found.append(f"end_reason {got['end_reason']} against {want['end_reason']}")
    return found


def main(argv: list[str]) -> int:
    if argv not in (["record"], ["check"]):
        print("usage: python tests/kernel_baseline.py record|check", file=sys.stderr)
        return 2
    sys.path.insert(0, str(ROOT))
    if argv == ["record"]:
        rows = []
        for name, kernel in cases():
            start = time.perf_counter()
            rows.append(run(name, kernel))
            print(f"{name} {kernel}: {rows[-1]['depth']} m, {time.perf_counter() - start:.1f} s", flush=True)
        with TABLE.open("w", newline="") as file:
            file.write("# every shipped scene on both kernels: python tests/kernel_baseline.py record\n")
            writer = csv.DictWriter(file, FIELDS)
            writer.writeheader()
            writer.writerows(rows)
        return 0
    failed = 0
    for want in read():
        got = run(want["scene"], want["kernel"])
        moved = differences(want, got)
        failed += bool(moved)
        within = ", ".join(
            [f"{key} {float(got[key]) / float(want[key]) - 1:+.1e}" for key in ("depth", "path_length")]
            + [f"turn {float(got['axis_angle_change']) - float(want['axis_angle_change']):+.1e} deg"]
        )
        print(f"{want['scene']} {want['kernel']}: " + ("; ".join(moved) if moved else f"within ({within})"), flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
