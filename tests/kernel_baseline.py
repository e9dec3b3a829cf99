"""The results a change of the load kernel's structure must keep: every shipped scene on both kernels.

Usage (from the repository root)::

    .venv/bin/python tests/kernel_baseline.py record     # writes tests/kernel_baseline.csv
    .venv/bin/python tests/kernel_baseline.py ranges     # measures the turning rows' round-off ranges into it
    .venv/bin/python tests/kernel_baseline.py check      # runs them again and prints the differences

``record`` runs every shipped scene (``cases/*.toml``) as shipped, once with ``numerics.kernel = "numpy"``
and once with ``"compiled"`` (where the compiled kernel covers the scene), and writes its depth, path length
and axis turn with every digit.  The committed table is the baseline that ``tests/fem_loads/test_kernel_baseline.py``
(a slow test) holds the code to:

* a straight scene (its axis turns less than 1e-6 degrees) within 1e-9 of its depth and path length;
* a turning scene within 1e-5 of its path length (relative) and 1e-3 degrees of its turn, and its depth
  within 1e-5 too.

A turning run amplifies round-off (a reordered sum moves its last digits, and the turn grows them), which is
why it is held to less.  In a run that tumbles or turns after perforating, the amplified round-off alone can
exceed those tolerances: the same code on another processor (whose BLAS and SIMD sum in another order) moves
them, and so does an impact speed a few hundred ulps away.  ``ranges`` measures that round-off range for each
turning row, as the spread of depth, path length and turn over runs with the impact speed scaled by
``1 + d`` for each ``d`` of :data:`PERTURBATIONS` (the code as it is, on the machine it runs on), and the check
allows each turning row :data:`RANGE_MARGIN` times its range where that exceeds the fixed tolerance: a result
that moves beyond its own round-off has changed.  Record again only for a change that is meant to change
results, and say so.
"""

from __future__ import annotations

import csv
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
TABLE = Path(__file__).resolve().with_name("kernel_baseline.csv")
FIELDS = ("scene", "kernel", "depth", "path_length", "axis_angle_change", "end_reason")
#: each turning row's round-off range (m, m, degrees; empty for a straight row): ``ranges``
RANGES = {"depth": "depth_range", "path_length": "path_range", "axis_angle_change": "turn_range"}
KERNELS = ("numpy", "compiled")
#: the axis turn (degrees) under which a scene counts as straight
STRAIGHT_TURN = 1e-6
STRAIGHT_TOLERANCE = 1e-9
TURNING_TOLERANCE = 1e-5
TURNING_TURN_TOLERANCE = 1e-3
#: the relative changes of the impact speed whose runs measure a turning row's round-off range (a few hundred ulps)
PERTURBATIONS = (-3e-13, -2e-13, -1e-13, 1e-13, 2e-13, 3e-13)
#: the multiple of its round-off range a turning row may move (two samples of one spread differ by up to it)
RANGE_MARGIN = 2.0


def cases() -> list[tuple[str, str]]:
    """``(scene, kernel)`` of every shipped scene on each kernel that covers it."""
    from cases import SHIPPED_SCENES, load_scene, scene_path

    found = []
    for name in SHIPPED_SCENES:
        scene = load_scene(scene_path(name))
        found += [(name, kernel) for kernel in KERNELS if kernel == "numpy" or scene.compilable]
    return found


def run(name: str, kernel: str, perturbation: float = 0.0) -> dict[str, str]:
    """One row of the table: the scene as shipped, on ``kernel`` (its impact speed scaled by ``1 + perturbation``)."""
    from cases import load_scene, run_scene, scene_path, summarise

    overrides: dict[str, object] = {"numerics.kernel": kernel}
    if perturbation:
        overrides["impact.speed"] = load_scene(scene_path(name)).impact.speed * (1.0 + perturbation)
    summary = summarise(run_scene(load_scene(scene_path(name), overrides)))
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


def write(rows: list[dict[str, str]]) -> None:
    with TABLE.open("w", newline="") as file:
        file.write("# every shipped scene on both kernels: python tests/kernel_baseline.py record, then ranges\n")
        writer = csv.DictWriter(file, (*FIELDS, *RANGES.values()))
        writer.writeheader()
        writer.writerows(rows)


def turning(row: dict[str, str]) -> bool:
    return abs(float(row["axis_angle_change"])) >= STRAIGHT_TURN


def round_off_ranges(name: str, kernel: str) -> dict[str, str]:
    """The spread of each result over the runs of :data:`PERTURBATIONS` (module docstring)."""
    runs = [run(name, kernel, perturbation) for perturbation in PERTURBATIONS]
    return {
        column: repr(max(float(r[key]) for r in runs) - min(float(r[key]) for r in runs))
        for key, column in RANGES.items()
    }


def differences(want: dict[str, str], got: dict[str, str]) -> list[str]:
    """What moved beyond the tolerances (module docstring), one line each; empty when nothing did."""
    straight = not turning(want)
    tolerance = STRAIGHT_TOLERANCE if straight else TURNING_TOLERANCE
    found = []
    for key in RANGES:
        a, b = float(want[key]), float(got[key])
        if key == "axis_angle_change":
            allowed = STRAIGHT_TURN if straight else TURNING_TURN_TOLERANCE  # degrees
        else:
            allowed = tolerance * abs(a)
        if not straight:
            allowed = max(allowed, RANGE_MARGIN * float(want.get(RANGES[key]) or 0.0))
        if abs(b - a) > allowed:
            found.append(f"{key} {b!r} against {a!r} (moved {b - a:+.2e}; allowed {allowed:.2e})")
    if got["end_reason"] != want["end_reason"]:
        found.append(f"end_reason {got['end_reason']} against {want['end_reason']}")
    return found


def main(argv: list[str]) -> int:
    if argv not in (["record"], ["ranges"], ["check"]):
        print("usage: python tests/kernel_baseline.py record|ranges|check", file=sys.stderr)
        return 2
    sys.path.insert(0, str(ROOT))
    if argv == ["record"]:
        rows = []
        for name, kernel in cases():
            start = time.perf_counter()
            rows.append(run(name, kernel))
            print(f"{name} {kernel}: {rows[-1]['depth']} m, {time.perf_counter() - start:.1f} s", flush=True)
        write(rows)
        return 0
    if argv == ["ranges"]:  # the recorded results kept, each turning row's round-off range measured anew
        rows = read()
        for row in rows:
            row.update(
                round_off_ranges(row["scene"], row["kernel"]) if turning(row) else dict.fromkeys(RANGES.values(), "")
            )
            print(f"{row['scene']} {row['kernel']}: " + ", ".join(row[c] or "-" for c in RANGES.values()), flush=True)
        write(rows)
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
