"""The compiled step (numerics.kernel = "compiled") runs the scenes as the numpy reference does.

Bound: 1e-9 relative in depth for tests 2, 3, 4, 6 and #1 (measured: at most 5.5e-11).  Test 5 (an
oblique impact with an attack angle) measured 8.4e-10 and #2-#4 up to 1.1e-7: their pitch motion
amplifies the round-off in which the two loads differ (the compiled kernel sums with fused
multiply-adds in SIMD lanes), and #3 and #4 go unstable and leave the target, where a round-off
difference can also move a Dormand-Prince step-size decision.  The numpy path differs from itself
by as much with its sums taken in another order (#3: 1.1e-7).  Measured against the scene's
own tolerance, rtol (1e-5 for test 5, 1e-6 for #2-#4), the two paths agree about as closely as
the scene asks for. The calibrated family (`paper_fitted_p*`, 2.12 times the transverse inertia) turns
more slowly and longer before it stops, and #4 of it differs by 1.07e-6 = 1.07 rtol at the end: the
amplification of a turning run is not bounded by the local tolerance. So the bound for the scenes that
turn is 10 rtol (1e-5 here): still some twenty times below the time error of these numerics themselves
(1.8e-4 in depth for #3 near its critical speed, docs/accuracy.md), so the kernels agree far more closely
than the scene is accurate.
"""

from __future__ import annotations

from pathlib import Path

import pytest

import cases
from cases import SHIPPED_SCENES, load_scene, run_scene, scene_path

LAWS = Path(cases.__file__).parent / "laws" / "soil_laws.py"
OVERBURDEN = {"c0": 1.718e7, "c2": 2282.22, "unit_weight": 1.8e4, "lateral_ratio": 0.5}
MIXED_LAYERS = {
    "target.layers": [
        {"thickness": 1.0, "law": {"function": f"{LAWS}:cavity_expansion", "parameters": {"c0": 1e7, "c2": 2e3}}},
        {"law": "soil"},
    ]
}
STABLE = {"forrestal_luk_test2", "forrestal_luk_test3", "forrestal_luk_test4", "forrestal_luk_test6", "paper_p1"}


def _depth_and_record(name: str, kernel: str, overrides: dict | None = None):
    result = run_scene(load_scene(scene_path(name), {**(overrides or {}), "numerics.kernel": kernel}))
    trajectory = result.trajectory
    return abs(float(trajectory.position[-1][2])), trajectory, result.scene


def _compare(name: str, overrides: dict | None = None) -> tuple[float, float]:
    numpy_depth, numpy_run, numpy_scene = _depth_and_record(name, "numpy", overrides)
    compiled_depth, compiled_run, compiled_scene = _depth_and_record(name, "compiled", overrides)
    assert numpy_scene.numerics.kernel == "numpy" and compiled_scene.numerics.kernel == "compiled"
    assert numpy_run.end_reason == compiled_run.end_reason
    bound = 1e-9 if name in STABLE else 10 * numpy_scene.numerics.rtol
    return abs(compiled_depth - numpy_depth) / numpy_depth, bound


@pytest.mark.parametrize(
    ("name", "overrides"),
    [("forrestal_luk_test2", None), ("paper_p3", {"numerics.mesh_size": 0.04, "impact.speed": 800.0})],
)
def test_compiled_and_numpy_kernels_agree(name, overrides):
    difference, _ = _compare(name, overrides)
    assert difference <= 1e-9


@pytest.mark.slow
@pytest.mark.parametrize("name", SHIPPED_SCENES)
def test_compiled_and_numpy_kernels_agree_on_every_shipped_scene(name):
    difference, bound = _compare(name)
    assert difference <= bound, f"{name}: {difference:.3g} > {bound:g}"


def test_auto_is_numpy_for_one_run_and_compiled_for_a_study():
    scene = load_scene(scene_path("forrestal_luk_test2"))
    assert scene.numerics.kernel == "auto"
    assert scene.with_kernel(many_runs=False).numerics.kernel == "numpy"
    assert scene.with_kernel(many_runs=True).numerics.kernel == "compiled"
    friction = load_scene(scene_path("forrestal_luk_test2"), {"effects.friction.model": "coulomb"})
    assert friction.with_kernel(many_runs=True).numerics.kernel == "compiled"  # the kernel has every effect
    mixed = load_scene(scene_path("forrestal_luk_test2"), MIXED_LAYERS)
    assert mixed.with_kernel(many_runs=True).numerics.kernel == "numpy"  # the kernel calls one user function
    explicit = load_scene(scene_path("forrestal_luk_test2"), {"numerics.kernel": "numpy"})
    assert explicit.with_kernel(many_runs=True).numerics.kernel == "numpy"


def test_compiled_kernel_refuses_layers_of_a_user_law_and_a_built_in_one():
    from cases import InputError

    with pytest.raises(InputError, match="numerics.kernel"):
        load_scene(scene_path("forrestal_luk_test2"), {**MIXED_LAYERS, "numerics.kernel": "compiled"})


#: every effect and law family the compiled step computes, as variants of test 2 and #3 (at 800 m/s on a 40 mm
#: mesh, where the shipped law keeps it stable)
VARIANTS = {
    "coulomb": {"effects.friction.model": "coulomb", "effects.friction.coefficient": 0.1},
    "capped": {"effects.friction.model": "capped", "effects.friction.coefficient": 0.3, "effects.friction.cap": 3e6},
    "free surface": {"effects.free_surface.depth": 0.5, "effects.free_surface.surface_fraction": 0.3},
    "layers": {"target.layers": [{"thickness": 1.0, "law": "softer_soil"}, {"law": "soil"}]},
    "centred": {"effects.contact": "centred"},
    "no separation": {"effects.separation": False},
    "polynomial": {"target.law": {"model": "polynomial", "c0": 1.5e7, "c1": 2e4, "c2": 1500.0}},
    "power": {"target.law": {"model": "power", "c0": 1.5e7, "c": 3e4, "n": 1.5}},
    "overburden": {"target.law": {"A": 1.718, "sigma_0": 1e7, "B": 1.227, "rho_0": 1860.0, "depth_gradient": 2e6}},
    "user law": {"target.law": {"function": f"{LAWS}:overburden", "parameters": OVERBURDEN}},
}


@pytest.mark.parametrize("variant", list(VARIANTS))
@pytest.mark.parametrize(
    ("name", "overrides"),
    [
        ("forrestal_luk_test2", {"numerics.mesh_size": 0.03}),
        ("paper_p3", {"numerics.mesh_size": 0.04, "impact.speed": 800.0}),
    ],
)
@pytest.mark.slow  # seconds of runs: CI's slow step
def test_compiled_and_numpy_kernels_agree_on_every_effect(name, overrides, variant):
    """1e-9 for test 2; #3 turns under some of these laws and effects (the polynomial law's, by 1e-6 relative),
    and there, as for the shipped scenes that turn, 10 rtol bounds the difference."""
    difference, bound = _compare(name, {**overrides, **VARIANTS[variant]})
    assert difference <= bound
