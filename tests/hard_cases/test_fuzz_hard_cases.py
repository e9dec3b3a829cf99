"""Fuzzing the hard cases of the integration: strong and weak targets, small and large projectiles, slow and fast
impacts, coarse and fine fixed steps and tolerances.

Each drawn scene is run twice: with the drawn numerics, and with Dormand-Prince at rtol 1e-9 on the same mesh
(the converged reference in time).  The drawn run must end within 2 % of the reference's depth and by twice its
stop time, or carry a warning that says why it may not; no fixed-step run may end by the time limit without a
warning.  The draws are derandomised (the same every run) and few in the default suite; the slow variant draws
more; ``PENETRATE_FUZZ_SCALE=N`` multiplies both and draws new ones (docs/numerics.md, "The end of a run").
"""

from __future__ import annotations

import functools
import math
import os

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from cases import run_scene, summarise
from cases.scene import scene_from_dict

SCALE = float(os.environ.get("PENETRATE_FUZZ_SCALE", "1"))
EXPLORING = "PENETRATE_FUZZ_SCALE" in os.environ


def fuzz(examples: int):
    return settings(
        max_examples=max(1, round(examples * SCALE)),
        derandomize=not EXPLORING,
        deadline=None,
        suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much],
    )


def log_uniform(low: float, high: float):
    return st.floats(math.log10(low), math.log10(high)).map(lambda e: 10.0**e)


def scene_data(diameter: float, static: float, density: float, speed: float) -> dict:
    """A steel CRH 3 ogive of 8 calibres, normal impact, a cavity-expansion target; a coarse mesh (a third of the
    diameter, second-order, exact normals), since the property is about time, not space."""
    return {
        "projectile": {"diameter": diameter, "length": 8 * diameter, "nose": {"shape": "ogive", "crh": 3.0}},
        "target": {"law": {"model": "polynomial", "c0": static, "c2": density}},
        "impact": {"speed": speed},
        "numerics": {"mesh_size": diameter / 3, "quadrature_order": 2, "kernel": "compiled", "time_limit": 2.0},
    }


@functools.lru_cache(maxsize=64)
def reference(diameter: float, static: float, density: float, speed: float) -> tuple[float, float, str]:
    """Depth (m), stop time (s) and end reason of the scene at Dormand-Prince rtol 1e-9."""
    data = scene_data(diameter, static, density, speed)
    data["numerics"].update({"integrator": "dopri54", "rtol": 1e-9})
    summary = summarise(run_scene(scene_from_dict(data)))
    return summary.depth, summary.final_time, summary.end_reason


hard_scenes = st.fixed_dictionaries(
    {
        # a few diameters, so that the meshes are shared between draws
        "diameter": st.sampled_from([0.01, 0.03, 0.1, 0.5]),
        "static": log_uniform(1e6, 1e9),  # Pa: a weak soil to a strong concrete or rock
        "density": st.floats(1400.0, 2700.0),
        "speed": st.floats(50.0, 1500.0),
        "integrator": st.sampled_from(["rk4", "rk4", "dopri54"]),
        # the fixed step as a fraction of the converged stop time, so that no draw takes a million steps
        "fraction": log_uniform(2e-3, 0.5),
        "rtol": log_uniform(1e-8, 1e-2),
    }
)


def check(draw: dict) -> None:
    keys = (draw["diameter"], draw["static"], draw["density"], draw["speed"])
    depth, stop_time, end = reference(*keys)
    data = scene_data(*keys)
    if draw["integrator"] == "rk4":
        data["numerics"].update({"integrator": "rk4", "time_step": min(0.01, draw["fraction"] * stop_time)})
    else:
        data["numerics"].update({"integrator": "dopri54", "rtol": draw["rtol"]})
    summary = summarise(run_scene(scene_from_dict(data)))
    why = (draw, summary.depth, depth, summary.final_time, stop_time, summary.end_reason, summary.warnings)
    if end != "stopped":  # the reference itself ran out of time (a very deep shot): the run must say so too
        assert summary.warnings, why
        return
    if draw["integrator"] == "rk4" and summary.end_reason == "time_limit":
        assert summary.warnings, why
    close = abs(summary.depth / depth - 1) <= 0.02 and summary.final_time <= 2 * stop_time
    assert close or summary.warnings, why


@fuzz(6)
@given(hard_scenes)
def test_hard_runs_end_near_the_converged_run_or_say_why(draw):
    check(draw)


@pytest.mark.slow
@fuzz(40)
@given(hard_scenes)
def test_hard_runs_end_near_the_converged_run_or_say_why_many(draw):
    check(draw)
