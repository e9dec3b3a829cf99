"""Performance benchmarks (pytest-benchmark), outside the default test run.

Run them with ``./dev bench`` (``pytest tests/benchmarks --benchmark-only``);
the default ``pytest`` run skips them (``--benchmark-skip`` in pyproject.toml).
docs/performance.md quotes their medians and spreads.

* the DAFL load evaluation per surface point, numpy and the compiled kernel (numba), against a
  compiled lower bound: a plain C loop over the same arrays (docs/performance/lower_bound.py, which
  docs/performance/loads.py shares: built with the system C compiler, called once per 100
  evaluations so that the ctypes call does not count; the numba kernel likewise 100 times from
  compiled code);
* integrator steps per second (RK4-MK with a free load, and with the DAFL load);
* one full run of ``cases/forrestal_luk_test2.toml`` at its shipped settings
  (in process, and as a ``penetrate run`` process);
* the 72-run sweep of the 155 mm family (6 speeds x 4 projectiles x 3 disturbances).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cases import load_scene, prepare_projectile, run_scene, scene_path
from cases.run import RunStore
from cases.studies import Pool, Sweep, Variation, grid, read_variations, run_sweep
from cases.studies.paper import STUDY_NUMERICS
from docs.performance.lower_bound import benchmark_state, c_compiler, c_loop_call, compiled_call, median_per_call
from dynamics import RK4, FixedStep, RigidBody, State, simulate
from dynamics.quaternion import from_rotation_matrix

ROOT = Path(__file__).resolve().parents[2]
FAMILY_RATIOS = "0.4448,0.5042,0.5636,0.6230"  # the paper's projectiles #1-#4 (Lc/L)
FAMILY_SPEEDS = "700:1200:100"  # m/s


@pytest.mark.parametrize("depth", [-3.0, -0.3], ids=["embedded", "entering"])
@pytest.mark.parametrize("mesh_size", [0.04, 0.02, 0.01, 0.005])
def test_load_evaluation(benchmark, tmp_path, mesh_size, depth):
    """The numpy load (benchmarked), the compiled kernel and the C loop (extra_info), all on the same state."""
    if c_compiler() is None:
        pytest.skip("no C compiler for the compiled lower bound")
    scene = load_scene(scene_path("paper_p3"), {"numerics.mesh_size": mesh_size})
    loads = scene.loads(prepare_projectile(scene).quadrature)
    position, velocity, rotation, spin = benchmark_state(depth)
    n = len(loads)
    c_loop = c_loop_call(loads, position, velocity, rotation, spin, tmp_path)
    kernel = compiled_call(loads, position, velocity, rotation, spin)

    force, moment = loads(position, velocity, rotation, spin)
    reference = np.concatenate([rotation.T @ force, moment])
    np.testing.assert_allclose(c_loop(1), reference, rtol=0, atol=1e-9 * np.abs(reference).max())
    np.testing.assert_allclose(kernel(1), np.concatenate([force, moment]), rtol=0, atol=1e-12 * np.abs(reference).max())
    lower_bound, compiled = median_per_call(c_loop), median_per_call(kernel)
    benchmark(loads, position, velocity, rotation, spin)
    median = benchmark.stats.stats.median
    benchmark.extra_info.update(
        points=n,
        numpy_ns_per_point=median / n * 1e9,
        c_loop_us=lower_bound * 1e6,
        compiled_kernel_us=compiled * 1e6,
        numpy_to_c_loop=median / lower_bound,
        compiled_to_c_loop=compiled / lower_bound,
    )


def test_integrator_steps_free_load(benchmark):
    """RK4-MK steps per second with a load that costs nothing: the integrator's own overhead."""
    body = RigidBody(75.0, np.diag([0.25, 2.28, 2.28]))
    zero = np.zeros(3)

    def loads(position, velocity, rotation, angular_velocity):
        return zero, zero

    start = State(
        0.0, np.zeros(3), np.array([800.0, 0.0, 0.0]), from_rotation_matrix(np.eye(3)), np.array([0.0, 0.5, 2.0])
    )
    steps = 2000
    trajectory = benchmark(simulate, body, loads, start, RK4(), FixedStep(1e-5), time_limit=steps * 1e-5)
    assert trajectory.statistics["steps"] == steps
    benchmark.extra_info.update(steps=steps, steps_per_second=steps / benchmark.stats.stats.median)


@pytest.mark.parametrize("mesh_size", [0.04, 0.02, 0.01])
def test_integrator_steps_dafl(benchmark, mesh_size):
    """Steps per second of #3 at 900 m/s (a whole run to rest), against the surface points."""
    scene = load_scene(
        scene_path("paper_p3"),
        {
            "numerics.mesh_size": mesh_size,
            "numerics.integrator": "rk4",
            "numerics.time_step": 2e-5,
            "impact.speed": 900,
        },
    )
    run_scene(scene)  # prepare (mesh, mass properties, quadrature) outside the timing
    result = benchmark.pedantic(run_scene, args=(scene,), rounds=3, iterations=1)
    steps = result.trajectory.statistics["steps"]
    benchmark.extra_info.update(
        points=len(result.prepared.quadrature),
        steps=steps,
        steps_per_second=steps / benchmark.stats.stats.median,
        evaluations=result.trajectory.statistics["load_evaluations"],
    )


def test_one_run_in_process(benchmark):
    """``cases/forrestal_luk_test2.toml`` at its shipped settings, prepared data cached."""
    scene = load_scene(scene_path("forrestal_luk_test2"))
    run_scene(scene)
    result = benchmark.pedantic(run_scene, args=(scene,), rounds=7, iterations=1)
    benchmark.extra_info.update(points=len(result.prepared.quadrature), steps=result.trajectory.statistics["steps"])


def test_one_run_process(benchmark):
    """``penetrate run cases/forrestal_luk_test2.toml``: the whole command, interpreter start included."""
    command = [str(Path(sys.executable).parent / "penetrate"), "run", str(scene_path("forrestal_luk_test2")), "--json"]
    subprocess.run(command, check=True, capture_output=True)  # fill the disk cache
    benchmark.pedantic(
        subprocess.run, args=(command,), kwargs={"check": True, "capture_output": True}, rounds=7, iterations=1
    )


@pytest.mark.parametrize(("numerics", "cache"), [("study", "warm"), ("study", "cold"), ("shipped", "warm")])
def test_sweep_72_runs(benchmark, tmp_path, monkeypatch, numerics, cache):
    """The 155 mm family: 6 speeds x 4 projectiles x 3 disturbances on every core, into an empty store.

    ``study``: the numerics of ``penetrate paper`` (20 mm, 2e-5 s; cases.studies.paper.STUDY_NUMERICS);
    ``shipped``: the scene files' own (10 mm, 2e-5 s).  ``warm``: meshes and prepared
    projectiles already in the disk cache (a user's second sweep of the same family);
    ``cold``: an empty cache, so the sweep meshes four projectiles.
    """
    variations = [
        Variation({**g.values, **v.values})
        for g in grid(
            {
                "projectile.centre_of_mass_ratio": [float(x) for x in FAMILY_RATIOS.split(",")],
                "impact.speed": [700.0, 800.0, 900.0, 1000.0, 1100.0, 1200.0],
            }
        )
        for v in read_variations(ROOT / "docs" / "performance" / "disturbances.toml")
    ]
    assert len(variations) == 72
    sweep = Sweep.from_file(scene_path("paper_p3"), STUDY_NUMERICS if numerics == "study" else None, variations)
    rounds = iter(range(100))

    def setup():
        round_ = next(rounds)
        if cache == "cold":
            monkeypatch.setenv("PENETRATE_CACHE_DIR", str(tmp_path / f"cache-{round_}"))
        return (sweep, RunStore(tmp_path / f"store-{round_}"), Pool(progress=False)), {}

    if cache == "warm":
        run_sweep(sweep, RunStore(tmp_path / "fill"), Pool(progress=False))
    table = benchmark.pedantic(run_sweep, setup=setup, rounds=3, iterations=1).table()
    assert len(table) == 72 and ("error" not in table or table["error"].isna().all())
    benchmark.extra_info.update(
        runs=72, steps_total=int(table["steps"].sum()), points=int(table["surface_points"].iloc[0])
    )
