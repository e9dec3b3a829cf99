"""Targets beyond a level half-space: slabs that are perforated, gaps, inclined faces, ricochets.

Each run is checked against an independent truth: a 1-D integration of the nose through the slices of the target
(cases.reference.normal_impact, which uses the exact profile and no mesh), the equal work of a rate-independent law
through equal thicknesses, and the rotation of a whole scene about the Y axis.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np
import pytest

from cases import scene_path
from cases.reference.normal_impact import Layer, scene_slab_1d
from cases.run import prepare_projectile, run_scene
from cases.run.summary import summarise
from cases.scene import Scene, SceneError
from cases.scene.load import read_scene_data, scene_from_dict
from fem_loads.target import LayeredTarget

SLAB = {"layers": [{"thickness": 2.0, "law": "soil"}]}
GAPPED = {
    "layers": [{"thickness": 1.0, "law": "soil"}, {"thickness": 0.5, "law": "air"}, {"thickness": 1.0, "law": "soil"}]
}
# a rate-independent law: every element of the nose does the same work through the same thickness at any speed
STATIC = {"model": "polynomial", "c0": 17.18e6}


def shot(target: dict[str, Any], kernel: str = "numpy", **impact: float) -> Scene:
    """Forrestal and Luk's test 2 projectile (23.1 kg, 95.2 mm, CRH 3) at 280 m/s into ``target``."""
    data = read_scene_data(scene_path("forrestal_luk_test2"))
    data["target"] = target
    data["impact"].update(impact)
    data["numerics"]["kernel"] = kernel
    return scene_from_dict(data, "test 2")


def one_d(scene: Scene) -> tuple[float, float]:
    """The 1-D nose through the scene's target (:func:`scene_slab_1d`): residual velocity (m/s) and tip depth (m)."""
    return scene_slab_1d(scene, prepare_projectile(scene))


@pytest.mark.parametrize("kernel", ["numpy", "compiled"])
def test_a_slab_is_perforated_at_the_residual_velocity_of_the_1d_nose(kernel: str) -> None:
    scene = shot(SLAB, kernel)
    summary = summarise(run_scene(scene))
    residual, _ = one_d(scene)
    assert summary.end_reason == "perforated"
    assert 0.0 < residual < 280.0
    assert summary.residual_velocity == pytest.approx(residual, rel=5e-3)
    assert summary.exit_time > 0.0
    assert summary.exit_axis_angle < 1e-6 and summary.exit_attack_angle < 1e-6  # a straight shot stays straight


@pytest.mark.parametrize("time_step", [5e-4, 1e-4])
def test_coarse_fixed_steps_perforate_at_the_same_speed(time_step: float) -> None:
    # RK4 at fixed steps up to nearly a nose length of travel: no creep, no face crossed unresolved
    data = read_scene_data(scene_path("forrestal_luk_test2"))
    data["target"] = SLAB
    data["numerics"].update(integrator="rk4", time_step=time_step)
    del data["numerics"]["rtol"]
    scene = scene_from_dict(data, "test 2, RK4")
    summary = summarise(run_scene(scene))
    assert summary.end_reason == "perforated" and not summary.warnings
    assert summary.residual_velocity == pytest.approx(one_d(scene)[0], rel=5e-3)


def test_a_gap_costs_nothing_but_its_crossing() -> None:
    slab, gapped = (summarise(run_scene(shot(target))) for target in (SLAB, GAPPED))
    assert gapped.end_reason == slab.end_reason == "perforated"
    assert gapped.residual_velocity == pytest.approx(slab.residual_velocity, rel=1e-2)
    # and the 1-D model sees the same
    assert one_d(shot(GAPPED))[0] == pytest.approx(gapped.residual_velocity, rel=5e-3)


def test_with_a_rate_independent_law_a_gap_changes_nothing() -> None:
    static = {"layers": [dict(layer, law=STATIC if layer["law"] == "soil" else "air") for layer in GAPPED["layers"]]}
    whole = {"layers": [{"thickness": 2.0, "law": STATIC}]}
    slab, gapped = (summarise(run_scene(shot(target))) for target in (whole, static))
    assert gapped.end_reason == slab.end_reason == "perforated"
    # the same work through 2 m of the same law: the residual speeds agree to the mesh's round-off of the work
    assert gapped.residual_velocity == pytest.approx(slab.residual_velocity, rel=1e-4)


def test_a_thick_slab_stops_the_body_as_the_half_space_does() -> None:
    thick, half_space = (
        summarise(run_scene(shot(target)))
        for target in ({"layers": [{"thickness": 8.0, "law": "soil"}]}, {"law": "soil"})
    )
    assert thick.end_reason == half_space.end_reason == "stopped"
    assert math.isnan(thick.residual_velocity) and math.isnan(thick.exit_time)
    assert thick.depth == pytest.approx(half_space.depth, rel=1e-12)


def test_an_inclined_target_hit_vertically_is_the_level_target_hit_obliquely() -> None:
    # the whole scene turned by 30 deg about Y: the path and the axis's turn are the same
    level = summarise(run_scene(shot({"law": "soil"}, oblique_angle=30.0)))
    inclined = summarise(run_scene(shot({"law": "soil", "inclination": 30.0})))
    assert inclined.end_reason == level.end_reason
    assert inclined.path_length == pytest.approx(level.path_length, rel=1e-4)
    assert abs(inclined.axis_angle_change - level.axis_angle_change) < 0.01
    assert inclined.depth == pytest.approx(level.depth, rel=1e-4)  # depth below the face, not below Z = 0


def test_a_grazing_shot_ricochets() -> None:
    summary = summarise(run_scene(shot({"law": "soil"}, oblique_angle=80.0)))
    assert summary.end_reason == "ricocheted"
    assert summary.exit_time > 0.0 and summary.final_speed > 0.0
    assert 0.0 <= summary.exit_velocity_angle < 90.0  # leaving: the velocity points out of the front face
    assert math.isnan(summary.residual_velocity)


@pytest.mark.parametrize(
    ("target", "message"),
    [
        ({"layers": [{"thickness": -1.0, "law": "soil"}]}, "thickness"),
        ({"layers": [{"thickness": 0.5, "law": "air"}, {"law": "soil"}]}, "gap"),
        ({"layers": [{"thickness": 1.0, "law": "soil"}, {"thickness": 0.5, "law": "air"}]}, "gap"),
        ({"law": "soil", "inclination": 90.0}, "inclination"),
        ({"law": "soil", "inclination": -95.0}, "inclination"),
        ({"law": "air"}, "law"),
    ],
)
def test_bad_targets_are_refused_in_one_line(target: dict[str, Any], message: str) -> None:
    with pytest.raises(SceneError) as error:
        shot(target)
    text = str(error.value)
    assert message in text and "\n" not in text.strip()


def test_the_1d_slices_match_a_single_law_half_space() -> None:
    # the sliced 1-D force equals the one-law force wherever the nose lies in the first slice
    from cases.reference.normal_impact import axial_force, layered_axial_force

    scene = shot(SLAB)
    built = scene.target.build()
    assert isinstance(built, LayeredTarget)
    profile, law = prepare_projectile(scene).profile, built.laws[0]
    slices = [Layer(0.0, 2.0, law)]
    for depth in (0.05, 0.2, 0.5, 1.5):
        assert layered_axial_force(profile, slices, depth, 250.0) == pytest.approx(
            axial_force(profile, law, depth, 250.0, 0.0), rel=1e-9
        )
    assert layered_axial_force(profile, slices, 2.0 + profile.nose_length + 1e-9, 250.0) == 0.0
    assert np.isfinite(layered_axial_force(profile, slices, 2.0 + 0.5 * profile.nose_length, 250.0))
