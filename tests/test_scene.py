"""Scenes: the shipped files validate, overrides apply, bad input is explained."""

import pytest

from cases import SHIPPED_SCENES, SceneError, apply_overrides, load_scene, scene_from_dict, scene_key, scene_path
from cases.runner import projectile_geometry
from mesh import analytic_mass_properties

BASE = {
    "projectile": {"diameter": 0.0952, "length": 1.4, "nose": {"shape": "ogive", "crh": 3.0}, "mass": 23.1},
    "impact": {"speed": 280.0},
    "numerics": {"mesh_size": 0.01},
}


@pytest.mark.parametrize("name", SHIPPED_SCENES)
def test_shipped_scenes_validate(name):
    scene = load_scene(scene_path(name))
    assert scene.name == name


@pytest.mark.parametrize("number, ratio", [(1, 0.4448), (2, 0.5042), (3, 0.5636), (4, 0.6230)])
def test_paper_family_scenes_place_their_counterweight(number, ratio):
    scene = load_scene(scene_path(f"paper_p{number}"))
    geometry, densities = projectile_geometry(scene.projectile)
    props = analytic_mass_properties(geometry, *densities.values())
    assert props.mass == pytest.approx(75.67, rel=1e-9)
    assert props.centre_from_tip / 0.93 == pytest.approx(ratio, rel=1e-9)
    assert (scene.impact.speed, scene.impact.attack_angle, scene.impact.oblique_angle) == (1200, 1, 0)


@pytest.mark.parametrize("override, expected", [
    ("impact.attack_angle=120", "impact.attack_angle = 120: must be <= 90 (allowed: -90 <= impact.attack_angle <= 90 deg)"),
    ("impact.speed=-3", "impact.speed = -3: must be > 0 (allowed: 0 < impact.speed <= 10000 m/s)"),
    ("impact.speed=nan", "impact.speed = nan: must be a finite number"),
    ("impact.speed=inf", "impact.speed = inf: must be a finite number"),
    ("impact.colour=1", "impact.colour: unknown key (allowed here: angular_velocity, attack_angle,"),
    ("projectile.nose.crh=0.2", "projectile.nose.crh = 0.2: must be >= 0.5"),
    ("numerics.mesh_size=0", "numerics.mesh_size = 0: must be > 0 (allowed: 0 < numerics.mesh_size <= 10 m)"),
    ("numerics.geometry_order=3", "numerics.geometry_order = 3: input should be 1 or 2"),
    ("numerics.integrator=euler", "numerics.integrator = 'euler': input should be 'rk4' or 'dopri54'"),
    ("target.law=clay", "target.law: unknown law 'clay': must be one of softer_soil, soil,"),
    ("target.law={A=1,B=1,sigma_0=-1,rho_0=1}", "target.law.sigma_0 = -1: must be > 0"),
    ("projectile.nose.shape=sphere", "projectile.nose.shape = 'sphere': unknown shape (allowed: 'ogive', 'cone',"),
    ("impact.speed='fast'", "impact.speed = 'fast': input should be a valid number"),
    ("projectile.body_density=7850", "give mass or body_density, not both"),
    ("projectile.centre_of_mass=0.5", "centre_of_mass places a counterweight"),
])
def test_errors_name_the_field_and_the_allowed_range(override, expected):
    with pytest.raises(SceneError) as info:
        scene_from_dict(apply_overrides(BASE, [override]))
    message = str(info.value)
    assert expected in message and "\n" not in message


def test_overrides_parse_toml_values():
    data = apply_overrides(BASE, ["impact.speed=1120", "target.law=softer_soil",
                                  "impact.angular_velocity=[0.0, 1.5, 0.0]", "numerics.normals=\"mesh\""])
    scene = scene_from_dict(data)
    assert scene.impact.speed == 1120.0 and scene.target.law == "softer_soil"
    assert scene.impact.angular_velocity == (0.0, 1.5, 0.0) and scene.numerics.normals == "mesh"
    assert BASE["impact"]["speed"] == 280.0  # the input is not modified


@pytest.mark.parametrize("bad", ["impact.speed", "=3", "impact..speed=1", "impact.speed.value=3"])
def test_malformed_overrides(bad):
    with pytest.raises(SceneError, match="--set"):
        apply_overrides(BASE, [bad])


def test_unreadable_and_invalid_files(tmp_path):
    with pytest.raises(SceneError, match="cannot read the scene file"):
        load_scene(tmp_path / "missing.toml")
    bad = tmp_path / "bad.toml"
    bad.write_text("[impact\nspeed = 3")
    with pytest.raises(SceneError, match="not valid TOML"):
        load_scene(bad)
    binary = tmp_path / "binary.toml"
    binary.write_bytes(b"\xff\xfe\x00")
    with pytest.raises(SceneError, match="cannot read the scene file"):
        load_scene(binary)


def test_scene_key_follows_the_resolved_scene():
    a = scene_from_dict(BASE)
    b = scene_from_dict(apply_overrides(BASE, ["numerics.time_step=2e-5"]))  # the default, spelled out
    c = scene_from_dict(apply_overrides(BASE, ["impact.speed=281"]))
    assert scene_key(a) == scene_key(b) != scene_key(c)
