"""How run and sweep times grow: with surface points, with steps, with runs and with workers.

Usage (from the repository root; about 10 minutes on the 2-core machine)::

    .venv/bin/python -m docs.performance.scaling [--repeats 3] [--out docs/performance/scaling.md]

Measures, and writes as Markdown tables (medians, with the spread as min-max):

1. **Surface points**: one run of #3 at 900 m/s to rest at a fixed RK4 step of 2e-5 s (so every
   mesh takes the same ~4 800 steps), on the 40, 20, 10 and 5 mm meshes, with the numpy and the
   compiled kernel, in process (the prepared projectile cached, the compiled code loaded): the
   integration time, per step and per surface point.
2. **Steps**: the same run on the 20 mm mesh at RK4 steps of 4e-5, 2e-5 and 1e-5 s.
3. **Runs and workers**: ``penetrate sweep`` processes (the whole command, as a user runs it,
   each into an empty run store, meshes cached) of 6, 24 and 72 runs of the 155 mm family at the
   study numerics (20 mm, Dormand-Prince at rtol 1e-8, the compiled kernel), on 1 and 2 local
   worker processes, on a Dask ``LocalCluster`` of 2 worker processes, and on a cluster of a
   ``dask scheduler`` and two ``dask worker`` processes started from the command line (the
   clusters are started once, before their sweeps are timed; their workers keep the compiled code
   loaded between sweeps, as a real cluster would).
"""

from __future__ import annotations

import argparse
import os
import shutil
import socket
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

from cases import load_scene, run_scene, scene_path
from cases.studies.paper import STUDY_NUMERICS

ROOT = Path(__file__).resolve().parents[2]

MESHES = (0.04, 0.02, 0.01, 0.005)
TIME_STEPS = (4e-5, 2e-5, 1e-5)
FAMILY = [
    "--list",
    "docs/performance/disturbances.toml",
    "--grid",
    "projectile.centre_of_mass_ratio=0.4448,0.5042,0.5636,0.6230",
]
SUBSETS = {  # runs: what they vary (the three disturbances of docs/performance/disturbances.toml in each)
    6: [
        "--list",
        "docs/performance/disturbances.toml",
        "--grid",
        "projectile.centre_of_mass_ratio=0.4448,0.6230",
        "--grid",
        "impact.speed=900",
    ],
    24: [
        "--list",
        "docs/performance/disturbances.toml",
        "--grid",
        "projectile.centre_of_mass_ratio=0.4448,0.6230",
        "--grid",
        "impact.speed=700:1000:100",
    ],
    72: [*FAMILY, "--grid", "impact.speed=700:1200:100"],
}


def _spread(values: list[float], scale: float = 1.0, digits: int = 3) -> str:
    values = [v * scale for v in values]
    return f"{statistics.median(values):.{digits}g} ({min(values):.{digits}g}-{max(values):.{digits}g})"


def _run_times(overrides: dict, repeats: int) -> tuple[list[float], dict, int]:
    scene = load_scene(scene_path("paper_p3"), overrides)
    result = run_scene(scene)  # mesh, prepare and load the compiled code outside the timing
    times = [run_scene(scene).integration_time for _ in range(repeats)]
    return times, result.trajectory.statistics, len(result.prepared.quadrature)


def points_table(repeats: int) -> str:
    rows = [
        "| mesh | surface points | kernel | steps | integration (s) | per step (us) | per step and point (ns) |",
        "|---|---|---|---|---|---|---|",
    ]
    for size in MESHES:
        for kernel in ("numpy", "compiled"):
            overrides = {
                "numerics.mesh_size": size,
                "numerics.integrator": "rk4",
                "numerics.time_step": 2e-5,
                "impact.speed": 900.0,
                "numerics.kernel": kernel,
            }
            times, stats, points = _run_times(overrides, repeats)
            steps = stats["steps"]
            rows.append(
                f"| {size * 1000:g} mm | {points} | {kernel} | {steps} | {_spread(times)} |"
                f" {_spread(times, 1e6 / steps)} | {_spread(times, 1e9 / steps / points)} |"
            )
            print(rows[-1], flush=True)
    return "\n".join(rows)


def steps_table(repeats: int) -> str:
    rows = ["| RK4 step (s) | kernel | steps | integration (s) | per step (us) |", "|---|---|---|---|---|"]
    for step in TIME_STEPS:
        for kernel in ("numpy", "compiled"):
            overrides = {
                "numerics.mesh_size": 0.02,
                "numerics.integrator": "rk4",
                "numerics.time_step": step,
                "impact.speed": 900.0,
                "numerics.kernel": kernel,
            }
            times, stats, _ = _run_times(overrides, repeats)
            rows.append(
                f"| {step:g} | {kernel} | {stats['steps']} | {_spread(times)} |"
                f" {_spread(times, 1e6 / stats['steps'])} |"
            )
            print(rows[-1], flush=True)
    return "\n".join(rows)


def _sweep_seconds(runs: int, where: list[str], work: Path) -> float:
    store = Path(tempfile.mkdtemp(dir=work))
    numerics = [arg for key, value in STUDY_NUMERICS.items() for arg in ("--set", f"{key}={value}")]
    command = [
        str(Path(sys.executable).parent / "penetrate"),
        "sweep",
        "cases/paper_p3.toml",
        *numerics,
        *SUBSETS[runs],
        "--store",
        str(store),
        "--no-progress",
        *where,
    ]
    start = time.perf_counter()
    subprocess.run(command, cwd=ROOT, check=True, capture_output=True)
    seconds = time.perf_counter() - start
    shutil.rmtree(store)
    return seconds


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def sweeps_table(repeats: int) -> str:
    import distributed

    rows = ["| runs | where | wall (s) | per run (s) |", "|---|---|---|---|"]
    work = Path(tempfile.mkdtemp(prefix="scaling-"))
    # fill the mesh and prepared-projectile caches (and numba's) before any timing
    _sweep_seconds(72, ["--workers", "2"], work)
    places = {"1 local worker": ["--workers", "1"], "2 local workers": ["--workers", "2"]}
    for runs in (6, 24, 72):
        for name, where in places.items():
            times = [_sweep_seconds(runs, where, work) for _ in range(repeats)]
            rows.append(f"| {runs} | {name} | {_spread(times)} | {_spread(times, 1 / runs)} |")
            print(rows[-1], flush=True)
    env = dict(os.environ, PYTHONPATH=str(ROOT))
    with distributed.LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
        where = ["--scheduler", cluster.scheduler_address]
        _sweep_seconds(6, where, work)  # the workers import the project and load the compiled code once
        times = [_sweep_seconds(72, where, work) for _ in range(repeats)]
        rows.append(f"| 72 | Dask LocalCluster, 2 worker processes | {_spread(times)} | {_spread(times, 1 / 72)} |")
        print(rows[-1], flush=True)
    dask = str(Path(sys.executable).parent / "dask")
    address = f"tcp://127.0.0.1:{_free_port()}"
    scheduler = subprocess.Popen(
        [dask, "scheduler", "--host", "127.0.0.1", "--port", address.rsplit(":", 1)[1], "--dashboard-address", ":0"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    worker = subprocess.Popen(
        [dask, "worker", address, "--nworkers", "2", "--nthreads", "1", "--dashboard-address", ":0"],
        env=env,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.DEVNULL,
    )
    try:
        with distributed.Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=60)
        where = ["--scheduler", address]
        _sweep_seconds(6, where, work)
        times = [_sweep_seconds(72, where, work) for _ in range(repeats)]
        rows.append(
            f"| 72 | `dask scheduler` + `dask worker --nworkers 2` | {_spread(times)} | {_spread(times, 1 / 72)} |"
        )
        print(rows[-1], flush=True)
    finally:
        for proc in (worker, scheduler):
            proc.terminate()
        for proc in (worker, scheduler):
            proc.wait(timeout=30)
        shutil.rmtree(work, ignore_errors=True)
    return "\n".join(rows)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--repeats", type=int, default=3)
    parser.add_argument("--out", default=str(ROOT / "docs" / "performance" / "scaling.md"))
    parser.add_argument("--skip-sweeps", action="store_true")
    args = parser.parse_args(argv)
    parts = [
        "# Scaling (`docs/performance/scaling.py`)",
        "",
        f"Medians of {args.repeats} (min-max). Generated by `.venv/bin/python -m docs.performance.scaling"
        f" --repeats {args.repeats}`.",
        "",
        "## Run time and surface points (#3 at 900 m/s to rest, RK4 at 2e-5 s)",
        "",
        points_table(args.repeats),
        "",
        "## Run time and steps (20 mm)",
        "",
        steps_table(args.repeats),
    ]
    if not args.skip_sweeps:
        parts += [
            "",
            "## Sweep time, runs and workers (the 155 mm family, study numerics, whole command)",
            "",
            sweeps_table(args.repeats),
        ]
    Path(args.out).write_text("\n".join(parts) + "\n")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
