"""A/B timing of one load evaluation, this checkout against another commit, alternating processes.

Usage (from the repository root)::

    .venv/bin/python tests/benchmarks/load_ab.py --against REV [--rounds N]

Three workloads on the shipped test 2 at a yawed, pitching state in the target (the body 3 m deep, 300 m/s,
5 degrees of attack, 20 rad/s of pitch): the numpy load (``DAFLLoads``), the compiled kernel with the shipped
law, and the compiled kernel with friction (``mu = 0.1``).  Each round runs one process per side, A then B,
and swaps the order every round; a process times each workload's evaluations in repeats of a fixed count (after
a warm-up that leaves numba's loading out) and reports the median per evaluation.  The table gives each side's
median over the rounds, and the ratio (this checkout / REV).  The other side's code is imported from a
``git worktree`` of REV; both share the interpreter and the mesh cache.
"""

from __future__ import annotations

import argparse
import json
import os
import statistics
import subprocess
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]

PROBE = r"""
import json, math, sys, time
import numpy as np
from cases import load_scene, scene_path
from cases.run import prepare_projectile
from cases.run.compiled import compiled_modules
from dynamics.quaternion import rotation_matrix

_, layout = compiled_modules()
attack = math.radians(5.0)
nose_down = rotation_matrix(np.array([math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0]))
state = (
    np.array([0.0, 0.0, -3.0]),
    nose_down @ (300.0 * np.array([math.cos(attack), 0.0, -math.sin(attack)])),
    nose_down,
    np.array([0.0, 20.0, 0.0]),
)
shipped = load_scene(scene_path("forrestal_luk_test2"))
quadrature = prepare_projectile(shipped).quadrature
friction = load_scene(scene_path("forrestal_luk_test2"), {"effects.friction": {"model": "coulomb", "coefficient": 0.1}})
scenes = {"numpy": shipped, "compiled": shipped, "friction": friction}
loads = {name: scene.loads(quadrature) for name, scene in scenes.items()}
data = {name: layout.kernel_data(loads[name]) for name in ("compiled", "friction")}
out = np.empty(6)


def evaluate(name):
    if name == "numpy":
        loads["numpy"](*state)
    else:
        layout.dafl_kernel(data[name], *state, out)


result = {}
for name, count in (("numpy", 200), ("compiled", 2000), ("friction", 2000)):
    for _ in range(count // 10):
        evaluate(name)  # warm: numba's loading and the caches
    times = []
    for _ in range(7):
        start = time.perf_counter()
        for _ in range(count):
            evaluate(name)
        times.append((time.perf_counter() - start) / count * 1e6)
    result[name] = sorted(times)[3]
print(json.dumps(result))
"""


def _probe(checkout: Path) -> dict[str, float]:
    environment = {**os.environ, "PYTHONPATH": str(checkout)}
    done = subprocess.run(
        [sys.executable, "-c", PROBE], cwd=checkout, env=environment, capture_output=True, text=True, check=True
    )
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--against", required=True, help="the commit to compare with")
    parser.add_argument("--rounds", type=int, default=5)
    options = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        other = Path(folder) / "rev"
        subprocess.run(["git", "worktree", "add", "--detach", str(other), options.against], cwd=ROOT, check=True)
        try:
            sides = {"rev": other, "this": ROOT}
            times: dict[str, dict[str, list[float]]] = {side: {} for side in sides}
            for side in sides:
                _probe(sides[side])  # numba's compilation and the caches, untimed
            for round_ in range(options.rounds):
                order = ("rev", "this") if round_ % 2 == 0 else ("this", "rev")
                for side in order:
                    for name, value in _probe(sides[side]).items():
                        times[side].setdefault(name, []).append(value)
        finally:
            subprocess.run(["git", "worktree", "remove", "--force", str(other)], cwd=ROOT, check=True)
    print(f"| load evaluation | {options.against} | this checkout | ratio |")
    print("|---|---|---|---|")
    for name in times["this"]:
        a, b = statistics.median(times["rev"][name]), statistics.median(times["this"][name])
        print(f"| {name} | {a:.1f} us | {b:.1f} us | {b / a:.3f} |")
    return 0


if __name__ == "__main__":
    sys.exit(main())
