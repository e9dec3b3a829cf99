"""Plausible inputs: a value its field allows but no real target or projectile has (a unit slip: MPa for Pa, mm for
m, g/cm^3 for kg/m^3, g for kg) is refused in one line naming the field, the unit, the plausible range and the
value it probably meant; concrete's S, filled in from f'c, is held to its own limit after filling; an f'c outside
the data of Frew et al.'s fit warns; values at the edges of every plausible range are accepted."""

import math

import pytest
from pydantic import BaseModel
from support import schema_models

from cases import SHIPPED_SCENES, scene_path
from cases.scene import Scene, SceneError, apply_overrides, load_scene, read_scene_data, scene_from_dict
from cases.scene.plausible import (
    BODY_LENGTH,
    CONCRETE_STRENGTH,
    DENSITY,
    DIAMETER,
    DYNAMIC_DENSITY,
    FREE_SURFACE_DEPTH,
    LAYER,
    SHEAR_STRENGTH,
    STATIC_STRENGTH,
    STRENGTH,
    STRENGTH_GRADIENT,
    number,
    plausible_of,
    slip_hint,
)
from cases.scene.projectile import BodySpec, MassPropertiesSpec, ProfileNoseSpec
from fem_loads.resistance import concrete_strength_factor

TEST2 = "forrestal_luk_test2"
GROUT = "forrestal1996_concrete"  # 51 MPa concrete, S filled in
P3 = "paper_p3"  # counterweight, interior, body density
ERODED = "eroded_p3"  # a file's materials
CONCRETE = {"model": "concrete", "compressive_strength": 51e6, "density": 2300.0}
SOIL = {"A": 1.718, "sigma_0": 10e6, "B": 1.227, "rho_0": 1860.0}


def refusal(scene: str, overrides: dict) -> str:
    with pytest.raises(SceneError) as info:
        load_scene(scene_path(scene), overrides)
    message = str(info.value)
    assert "\n" not in message and message.startswith(f"{scene_path(scene)}: ")
    return message[len(str(scene_path(scene))) + 2 :]


@pytest.mark.parametrize(
    "scene, overrides, expected",
    [
        # stresses: MPa (or kPa) for Pa
        (
            GROUT,
            {"target.law": {**CONCRETE, "compressive_strength": 35, "S": 9.7}},
            "target.law.compressive_strength = 35 Pa: too low for concrete's compressive strength (allowed: 1e5 to"
            " 5e8 Pa, about 0.1-500 MPa); did you mean 35e6 (35 MPa)?",
        ),
        (
            GROUT,
            {"target.law.compressive_strength": 35000},
            "target.law.compressive_strength = 35000 Pa: too low for concrete's compressive strength (allowed: 1e5"
            " to 5e8 Pa, about 0.1-500 MPa); did you mean 35e6 (35000 kPa)?",
        ),
        (TEST2, {"target.law": {**SOIL, "sigma_0": 10}}, "target.law.sigma_0 = 10 Pa: too low for a target's strength"),
        (
            TEST2,
            {"target.law": {"model": "polynomial", "c0": 17.18, "c2": 2282.2}},
            "did you mean 17.18e6 (17.18 MPa)?",
        ),
        (TEST2, {"target.law": {"model": "power", "c0": 17.18, "c": 3e4, "n": 1.5}}, "target.law.c0 = 17.18 Pa:"),
        (TEST2, {"target.law": {**SOIL, "depth_gradient": 3}}, "depth_gradient = 3 Pa/m: too low for a strength's"),
        (
            TEST2,
            {"target.law": {**SOIL, "strength_table": [[0, 0], [1, 5]]}},
            "target.law.strength_table.1 = [1, 5]: its extra strength 5 Pa is too low for a target's static strength",
        ),
        (
            TEST2,
            {"effects.friction": {"model": "capped", "cap": 10}},
            "effects.friction.cap = 10 Pa: too low for a shear strength (allowed: 1000 to 1e10 Pa, about 0.001-10000"
            " MPa); did you mean 10e6 (10 MPa)?",
        ),
        # densities: g/cm^3 for kg/m^3
        (
            GROUT,
            {"target.law.density": 2.3},
            "target.law.density = 2.3 kg/m^3: too low for a solid's density (allowed: 20 to 25000 kg/m^3, about"
            " 0.02-25 g/cm^3); did you mean 2300 (2.3 g/cm^3)?",
        ),
        (TEST2, {"target.law": {**SOIL, "rho_0": 1.86}}, "target.law.rho_0 = 1.86 kg/m^3: too low"),
        (
            TEST2,
            {
                "target.law": {
                    "model": "locking_cavity_expansion",
                    "sigma_0": 10e6,
                    "rho_0": 1.86,
                    "locking_strain": 0.1,
                }
            },
            "did you mean 1860 (1.86 g/cm^3)?",
        ),
        (TEST2, {"target.law": {"model": "polynomial", "c0": 1e7, "c2": 2.28}}, "c2 = 2.28 kg/m^3: too low for a law"),
        (P3, {"projectile.body_density": 7.85}, "projectile.body_density = 7.85 kg/m^3: too low"),
        (P3, {"projectile.counterweight.density": 18}, "did you mean 18000 (18 g/cm^3)?"),
        (ERODED, {"projectile.materials": {"solid2": 18.0}}, "projectile.materials.solid2 = 18 kg/m^3: too low"),
        # lengths: mm for m
        (
            TEST2,
            {"projectile.diameter": 95.2},
            "projectile.diameter = 95.2: must be <= 10 (allowed: 0 < projectile.diameter <= 10 m); did you mean"
            " 0.0952 (95.2 mm)?",
        ),
        (
            TEST2,
            {"projectile.diameter": 4},
            "projectile.diameter = 4 m: too high for a projectile's diameter (allowed: 0.001 to 2.5 m, about 1-2500"
            " mm); did you mean 0.004 (4 mm)?",
        ),
        (TEST2, {"projectile.length": 1400}, "did you mean 1.4 (1400 mm)?"),
        (TEST2, {"numerics.mesh_size": 20}, "numerics.mesh_size = 20: must be <= 10"),
        (TEST2, {"numerics.mesh_size": 5}, "numerics.mesh_size = 5 m: too high for a mesh size"),
        (TEST2, {"numerics.mesh_size": 0.5}, "coarser than the projectile (allowed: numerics.mesh_size <= projectile"),
        (P3, {"projectile.interior.wall_thickness": 10}, "projectile.interior.wall_thickness = 10 m: too high"),
        (P3, {"projectile.interior.tail_thickness": 20}, "did you mean 0.02 (20 mm)?"),
        (P3, {"projectile.centre_of_mass": 520}, "projectile.centre_of_mass = 520: must be <= 100"),
        (P3, {"projectile.counterweight.start": 400, "projectile.counterweight.end": 600}, "(400 mm)?"),
        (TEST2, {"projectile.nose": {"shape": "blunt", "crh": 3.0, "flat_radius": 3}}, "flat_radius = 3 m: too high"),
        (TEST2, {"target.layers": [{"thickness": 1500, "law": "soil"}]}, "did you mean 1.5 (1500 mm)?"),
        (TEST2, {"effects.free_surface.depth": 500}, "effects.free_surface.depth = 500 m: too high"),
        # masses: g for kg, held to the body's size
        (
            TEST2,
            {"projectile.mass": 23100},
            "projectile: mass = 23100 kg: denser than 25000 kg/m^3, the densest solid, over the bounding cylinder"
            " (allowed: mass <= 249 kg for this diameter and length); did you mean 23.1 (23100 g)?",
        ),
        (
            TEST2,
            {
                "projectile.mass": None,
                "projectile.mass_properties": {
                    "mass": 23100,
                    "centre_of_mass": 0.8,
                    "axial_inertia": 0.03,
                    "transverse_inertia": 4.0,
                },
            },
            "mass_properties.mass = 23100 kg: denser than 25000 kg/m^3",
        ),
    ],
)
def test_a_unit_slip_is_refused_in_one_line(scene, overrides, expected):
    message = refusal(scene, overrides)
    assert expected in message, message
    assert "allowed" in message and ("did you mean" in message or "mesh_size" in message), message


@pytest.mark.parametrize("layered", [False, True])
def test_s_filled_in_from_a_tiny_strength_is_refused_after_filling(layered):
    """f'c = 35 (meant as MPa) gives S = 82.6 (35e-6)^-0.544 = 21 900: refused against S's own limit (1000), naming
    f'c and the value it probably meant, where S was accepted before."""
    law = {**CONCRETE, "compressive_strength": 35}
    overrides = {"target.layers": [{"thickness": 0.2, "law": law}]} if layered else {"target.law": law}
    where = "target.layers.0.law" if layered else "target.law"
    assert concrete_strength_factor(35) == pytest.approx(21928, rel=1e-4)
    assert refusal(GROUT, overrides) == (
        f"{where}.S = 21900 filled in from compressive_strength = 35 Pa by Frew et al.'s fit: allowed S <= 1000;"
        " is compressive_strength in Pa? did you mean 35e6 (35 MPa)?"
    )


def test_s_is_checked_before_its_source_and_the_source_after():
    """Below about 10.2 kPa f'c fills in an S above 1000 (refused as S); between that and the plausible 0.1 MPa,
    S is within its limit and f'c itself is refused."""
    edge = (82.6 / 1000) ** (1 / 0.544) * 1e6  # Pa: S = 1000
    assert concrete_strength_factor(edge) == pytest.approx(1000.0, rel=1e-12)
    below = refusal(GROUT, {"target.law.compressive_strength": 0.99 * edge})
    assert below.startswith("target.law.S = ") and "filled in from compressive_strength = 10" in below, below
    above = refusal(GROUT, {"target.law.compressive_strength": 1.01 * edge})
    assert above.startswith("target.law.compressive_strength = 10") and "too low" in above, above


@pytest.mark.parametrize(
    "strength, warns",
    [(51e6, False), (13e6, False), (60e6, False), (12e6, True), (100e6, True), (0.2e6, True), (400e6, True)],
)
def test_a_strength_outside_the_data_of_the_fit_warns(strength, warns):
    """Frew et al.'s S outside the about 13-60 MPa of its data (docs/laws.md) is an extrapolation: the scene runs,
    and says so naming the source and the range."""
    scene = load_scene(scene_path(GROUT), {"target.law.compressive_strength": strength})
    assert math.isclose(scene.target.law.S, concrete_strength_factor(strength), rel_tol=1e-12)
    if not warns:
        assert scene.warnings == []
        return
    (line,) = scene.warnings
    assert line.startswith(f"target.law.compressive_strength = {number(strength / 1e6)} MPa lies outside the 13-60")
    assert "Frew et al." in line and "(Int. J. Impact Eng. 21, 1998)" in line and "extrapolation" in line
    assert "\n" not in line


def test_a_given_s_does_not_warn_and_layers_are_named():
    given = load_scene(scene_path(GROUT), {"target.law": {**CONCRETE, "compressive_strength": 100e6, "S": 5.0}})
    assert given.warnings == []
    layered = load_scene(
        scene_path(GROUT),
        {"target.layers": [{"thickness": 0.5, "law": "soil"}, {"law": {**CONCRETE, "compressive_strength": 100e6}}]},
    )
    (line,) = layered.warnings
    assert line.startswith("target.layers.1.law.compressive_strength = 100 MPa lies outside")
    assert "give target.layers.1.law.S" in line


def test_the_shipped_scenes_are_plausible_and_warn_of_nothing():
    for name in SHIPPED_SCENES:
        assert load_scene(scene_path(name)).warnings == [], name


PLACED = {"projectile.counterweight.start": 0.4, "projectile.counterweight.end": 0.6}  # no mass to place it for


@pytest.mark.parametrize("edge", ["low", "high"])
@pytest.mark.parametrize(
    "scene, plausible, overrides",
    [
        (GROUT, CONCRETE_STRENGTH, lambda v: {"target.law.compressive_strength": v}),
        (GROUT, DENSITY, lambda v: {"target.law.density": v}),
        (TEST2, STRENGTH, lambda v: {"target.law": {**SOIL, "sigma_0": v}}),
        (TEST2, DENSITY, lambda v: {"target.law": {**SOIL, "rho_0": v}}),
        (
            TEST2,
            DENSITY,
            lambda v: {
                "target.law": {"model": "locking_cavity_expansion", "sigma_0": 1e7, "rho_0": v, "locking_strain": 0.1}
            },
        ),
        (TEST2, STRENGTH_GRADIENT, lambda v: {"target.law": {**SOIL, "depth_gradient": v}}),
        (TEST2, STATIC_STRENGTH, lambda v: {"target.law": {**SOIL, "strength_table": [[0.0, 0.0], [1.0, v]]}}),
        (TEST2, STATIC_STRENGTH, lambda v: {"target.law": {"model": "polynomial", "c0": v, "c2": 2000.0}}),
        (TEST2, STATIC_STRENGTH, lambda v: {"target.law": {"model": "power", "c0": v, "c": 3e4, "n": 1.5}}),
        (TEST2, DYNAMIC_DENSITY, lambda v: {"target.law": {"model": "polynomial", "c0": 1e7, "c2": v}}),
        (TEST2, SHEAR_STRENGTH, lambda v: {"effects.friction": {"model": "capped", "cap": v}}),
        (TEST2, LAYER, lambda v: {"target.layers": [{"thickness": v, "law": "soil"}]}),
        (TEST2, FREE_SURFACE_DEPTH, lambda v: {"effects.free_surface.depth": v}),
        (P3, DENSITY, lambda v: {"projectile.body_density": v, **PLACED}),
        (P3, DENSITY, lambda v: {"projectile.counterweight.density": v, **PLACED}),
        (ERODED, DENSITY, lambda v: {"projectile.materials": {"solid2": v}}),
    ],
)
def test_the_edges_of_the_plausible_ranges_are_accepted(scene, plausible, overrides, edge):
    """Each range at both of its ends, and 0 where a term may be left out."""
    for value in [getattr(plausible, edge)] + ([0.0] if plausible.zero and edge == "low" else []):
        assert isinstance(load_scene(scene_path(scene), overrides(value)), Scene), value
    outside = plausible.low * 0.99 if edge == "low" else plausible.high * 1.01
    with pytest.raises(SceneError, match="too (low|high) for"):
        load_scene(scene_path(scene), overrides(outside))


@pytest.mark.parametrize("diameter, length", [(DIAMETER.low, 8 * DIAMETER.low), (DIAMETER.high, BODY_LENGTH.high)])
def test_the_smallest_and_largest_projectiles_are_accepted(diameter, length):
    """A 1 mm pellet and a 2.5 m, 20 m body, each as heavy as the densest solid allows over its cylinder (or the
    hard limit of a mass, 1e6 kg)."""
    heaviest = min(DENSITY.high * math.pi / 4 * diameter**2 * length, 1e6 / 0.999)
    projectile = {"diameter": diameter, "length": length, "nose": {"shape": "ogive", "crh": 3.0}}
    scene = scene_from_dict(
        {
            "projectile": {**projectile, "mass": 0.999 * heaviest},
            "impact": {"speed": 300.0},
            "numerics": {"mesh_size": min(diameter / 2, 0.5)},
        }
    )
    assert scene.projectile.diameter == diameter and scene.projectile.mass == pytest.approx(0.999 * heaviest)


def test_every_si_quantity_of_the_schema_has_a_plausible_range_or_a_reason():
    """The one table: every field in Pa, Pa/m, kg/m^3 or m names a range of cases/scene/plausible.py, but for the
    few held to the body otherwise (the mass, by its mean density; a measured profile, by the shank radius)."""
    exempt = {(ProfileNoseSpec, "points"), (BodySpec, "points"), (MassPropertiesSpec, "mass")}
    seen, missing = set(), []

    def walk(model: type[BaseModel]) -> None:
        if model in seen:
            return
        seen.add(model)
        for name, info in model.model_fields.items():
            extra = info.json_schema_extra if isinstance(info.json_schema_extra, dict) else {}
            physical = extra.get("unit") in ("Pa", "Pa/m", "kg/m^3", "m")
            if physical and plausible_of(info) is None and (model, name) not in exempt:
                missing.append(f"{model.__name__}.{name}")
            for inner in schema_models(info.annotation):
                walk(inner)

    walk(Scene)
    assert not missing, missing


def test_a_slip_is_suggested_only_when_it_lands_in_the_range():
    assert slip_hint(35.0, "Pa", CONCRETE_STRENGTH.low, CONCRETE_STRENGTH.high) == "did you mean 35e6 (35 MPa)?"
    assert slip_hint(1e-5, "Pa", CONCRETE_STRENGTH.low, CONCRETE_STRENGTH.high) == ""  # 10 kPa even in GPa
    assert slip_hint(0.05, "Pa", CONCRETE_STRENGTH.low, CONCRETE_STRENGTH.high) == "did you mean 50e6 (0.05 GPa)?"
    assert slip_hint(155.0, "m", DIAMETER.low, DIAMETER.high) == "did you mean 0.155 (155 mm)?"
    assert slip_hint(1600.0, "kg", 0.1, 5.0) == "did you mean 1.6 (1600 g)?"
    assert STATIC_STRENGTH.holds(0.0) and not CONCRETE_STRENGTH.holds(0.0)


def test_a_mass_in_the_scene_file_is_held_to_its_flared_body():
    """A flare wider than the shank widens the bounding cylinder the heaviest mass is measured over."""
    data = read_scene_data(scene_path(TEST2))
    plain = DENSITY.high * math.pi / 4 * 0.0952**2 * 1.4
    flare = {"points": [[1.0, 0.0476], [1.4, 0.09]]}
    heavy = apply_overrides(data, {"projectile.mass": 1.5 * plain, "projectile.body": flare})
    assert scene_from_dict(heavy).projectile.mass == pytest.approx(1.5 * plain)
    with pytest.raises(SceneError, match="denser than 25000 kg/m"):
        scene_from_dict(apply_overrides(data, {"projectile.mass": 1.5 * plain}))


@pytest.mark.parametrize("speed, warns", [(405.0, False), (1000.0, False), (1001.0, True), (1201.0, True)])
def test_a_shot_into_concrete_above_a_kilometre_a_second_warns_of_mass_loss(speed, warns):
    """Above about 1 km/s a steel nose loses mass in concrete (docs/laws.md: Forrestal et al.'s 1996 shots, within
    6 % to 1069 m/s and 19.6 % too deep at 1201 m/s): the scene runs, says so in one line, and names the
    formulas to compare with."""
    lines = load_scene(scene_path(GROUT), {"impact.speed": speed}).warnings
    if not warns:
        assert lines == []
        return
    (line,) = lines
    assert line.startswith(f"impact.speed = {number(speed)} m/s into concrete (target.law): above about 1000 m/s")
    assert "loses mass" in line and "penetrate formulas SCENE" in line and "\n" not in line


def test_the_mass_loss_warning_names_the_concrete_layer_and_leaves_soil_alone():
    """Layers: the line names the concrete layer and no formulas (they take one homogeneous target); a soil at
    1200 m/s (the paper's shots) is not concrete and says nothing of mass loss."""
    (line,) = load_scene(scene_path("soil_over_sloping_concrete"), {"impact.speed": 1100.0}).warnings
    assert line.startswith("impact.speed = 1100 m/s into concrete (target.layers.1.law)")
    assert "formulas" not in line
    assert load_scene(scene_path(TEST2), {"impact.speed": 1200.0}).warnings == []
