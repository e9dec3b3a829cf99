"""Scenes: the shipped files validate, overrides apply and replace their alternatives, bad input is explained."""

import pytest

from cases import SHIPPED_SCENES, scene_path
from cases.scene import SceneError, apply_overrides, load_scene, parse_override, scene_from_dict, scene_key
from fem_loads import ResistanceLaw
from fem_loads.target import LayeredTarget
from mesh import ConeNose, analytic_mass_properties

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
    props = analytic_mass_properties(scene.projectile.shape(), *scene.projectile.densities().values())
    assert props.mass == pytest.approx(75.67, rel=1e-9)
    assert props.centre_from_tip / 0.93 == pytest.approx(ratio, rel=1e-9)
    assert (scene.impact.speed, scene.impact.attack_angle, scene.impact.oblique_angle) == (1200, 1, 0)


@pytest.mark.parametrize(
    "override, expected",
    [
        (
            "impact.attack_angle=120",
            "impact.attack_angle = 120: must be <= 90 (allowed: -90 <= impact.attack_angle <= 90 deg)",
        ),
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
        (
            "projectile.mass_properties={mass=20,centre_of_mass=0.7,axial_inertia=7,transverse_inertia=3}",
            "axial_inertia = 7: more than twice transverse_inertia = 3",
        ),
        ("projectile.centre_of_mass=0.5", "centre_of_mass places a counterweight"),
    ],
)
def test_errors_name_the_field_and_the_allowed_range(override, expected):
    with pytest.raises(SceneError) as info:
        scene_from_dict(apply_overrides(BASE, [parse_override(override)]))
    message = str(info.value)
    assert expected in message and "\n" not in message


def test_overrides_parse_toml_values():
    data = apply_overrides(
        BASE,
        [
            parse_override(text)
            for text in (
                "impact.speed=1120",
                "target.law=softer_soil",
                "impact.angular_velocity=[0.0, 1.5, 0.0]",
                'numerics.normals="mesh"',
            )
        ],
    )
    scene = scene_from_dict(data)
    assert scene.impact.speed == 1120.0 and scene.target.law == "softer_soil"
    assert scene.impact.angular_velocity == (0.0, 1.5, 0.0) and scene.numerics.normals == "mesh"
    assert BASE["impact"]["speed"] == 280.0  # the input is not modified


@pytest.mark.parametrize("bad", ["impact.speed", "=3", "impact..speed=1", "impact speed=1"])
def test_malformed_set_options(bad):
    with pytest.raises(SceneError, match="--set"):
        parse_override(bad)


def test_overrides_are_typed_pairs():
    with pytest.raises(SceneError, match="scene: impact.speed.value: impact.speed is a value, not a table"):
        apply_overrides(BASE, {"impact.speed.value": 3})
    with pytest.raises(SceneError, match="the key must be a dotted path"):
        apply_overrides(BASE, {"impact..speed": 3})
    # a value is used as it is: a table stays a table, a string a string (no text round trip)
    data = apply_overrides(
        BASE, {"target.law": {"A": 1.0, "sigma_0": 1e6, "B": 1.0, "rho_0": 1000.0}, "name": "speed=1120"}
    )
    scene = scene_from_dict(data)
    assert scene.target.law.A == 1.0 and scene.name == "speed=1120"


def test_an_override_replaces_its_alternatives():
    """A user who sets target.layers means the layers instead of the law, and so on for every one-of key."""
    layered = scene_from_dict(
        apply_overrides(
            {**BASE, "target": {"law": "soil"}},
            {"target.layers": [{"thickness": 1.0, "law": "soil"}, {"law": "softer_soil"}]},
        )
    )
    assert isinstance(layered.target.build(), LayeredTarget)
    back = scene_from_dict(apply_overrides({**BASE, "target": {"layers": [{"law": "soil"}]}}, {"target.law": "soil"}))
    assert back.target.layers is None and isinstance(back.target.build(), ResistanceLaw)
    cone = scene_from_dict(apply_overrides(BASE, {"projectile.nose.shape": "cone", "projectile.nose.half_angle": 12.0}))
    assert cone.projectile.nose.build() == ConeNose(12.0)
    coulomb = scene_from_dict(
        apply_overrides(
            {**BASE, "effects": {"friction": {"model": "capped", "cap": 1e7}}}, {"effects.friction.model": "coulomb"}
        )
    )
    assert coulomb.effects.friction.cap is None
    by_density = scene_from_dict(apply_overrides(BASE, {"projectile.body_density": 7850.0}))
    assert by_density.projectile.mass is None and by_density.projectile.body_density == 7850.0
    paper = load_scene(
        scene_path("paper_p3"), {"projectile.counterweight.start": 0.4, "projectile.counterweight.end": 0.6}
    )
    assert paper.projectile.mass is None and paper.projectile.centre_of_mass_ratio is None
    assert paper.projectile.shape().counterweight == (0.4, 0.6)
    given = load_scene(
        scene_path("paper_p3"),
        {
            "projectile.mass_properties": {
                "mass": 75.67,
                "centre_of_mass": 0.52,
                "axial_inertia": 0.25,
                "transverse_inertia": 4.0,
            }
        },
    )
    assert given.projectile.mass is None and given.projectile.shape().counterweight is None
    ratio = load_scene(scene_path("paper_p3"), {"projectile.centre_of_mass": 0.5})
    assert ratio.projectile.centre_of_mass_ratio is None and ratio.projectile.centre_target == 0.5


def test_two_alternatives_set_together_are_still_refused():
    with pytest.raises(SceneError, match="give law \\(homogeneous\\) or layers, not both"):
        load_scene(scene_path("forrestal_luk_test2"), {"target.law": "soil", "target.layers": [{"law": "soil"}]})
    # an override of a whole table replaces it as given: nothing is dropped from it
    with pytest.raises(SceneError, match="projectile.nose.crh: unknown key"):
        load_scene(scene_path("forrestal_luk_test2"), {"projectile.nose": {"shape": "cone", "half_angle": 9, "crh": 3}})


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
    b = scene_from_dict(apply_overrides(BASE, {"numerics.time_step": 2e-5}))  # the default, spelled out
    c = scene_from_dict(apply_overrides(BASE, {"impact.speed": 281}))
    assert scene_key(a) == scene_key(b) != scene_key(c)


TABLE = [[0.0, 0.0], [0.05, 0.03], [0.1, 0.044], [0.15, 0.0476]]  # m: a measured nose of test 2's projectile


def test_profile_nose_reads_from_a_file_and_builds(tmp_path):
    text = (
        scene_path("forrestal_luk_test2")
        .read_text()
        .replace('nose = { shape = "ogive", crh = 3.0 }\n', "")
        .replace(
            "[target]",
            '[projectile.nose]\nshape = "profile"\npoints = [\n'
            + "".join(f"  [{x}, {r}],\n" for x, r in TABLE)
            + "]\n\n[target]",
        )
    )
    path = tmp_path / "measured.toml"
    path.write_text(text)
    scene = load_scene(path)
    nose = scene.projectile.nose.build()
    assert nose.points == tuple(map(tuple, TABLE)) and scene.projectile.profile().nose_length == 0.15
    # a new shape drops the old shape's keys; the table becomes an ogive again
    back = load_scene(path, {"projectile.nose.shape": "ogive", "projectile.nose.crh": 3.0})
    assert back.projectile.nose.crh == 3.0


@pytest.mark.parametrize(
    "points, expected",
    [
        (TABLE[:2], "projectile.nose.points = [[0.0, 0.0], [0.05, 0.03]]: list should have at least 3 items"),
        ([[0.0, 0.01]] + TABLE[1:], "projectile: nose.points[0] = [0, 0.01]: must be the tip (allowed: [0, 0]"),
        (
            TABLE[:2] + [[0.05, 0.04]] + TABLE[3:],
            "nose.points[2] = [0.05, 0.04]: x must exceed the previous point's"
            " x = 0.05 m (allowed: x strictly increasing)",
        ),
        (
            TABLE[:2] + [[0.1, 0.02]] + TABLE[3:],
            "nose.points[2] = [0.1, 0.02]: r must be at least the previous"
            " point's r = 0.03 m (allowed: r non-decreasing)",
        ),
        (
            TABLE[:3] + [[0.15, 0.0477]],
            "nose.points[3]: r = 0.0477 m must be the shank radius (allowed: diameter/2"
            " = 0.0476 m, within 1e-06 of it)",
        ),
        (TABLE[:3] + [[0.15, float("nan")]], "projectile.nose.points.3.1 = nan: must be a finite number"),
        (TABLE[:3] + [[0.15, -1.0]], "projectile.nose.points.3.1 = -1.0: must be >= 0"),
        (TABLE[:3] + [[0.15]], "projectile.nose.points.3.1: missing (required)"),
        (TABLE[:3] + [[2.0, 0.0476]], "projectile: length = 1.4: must exceed the nose length 2 m"),
    ],
)
def test_bad_profile_noses_are_explained(points, expected):
    with pytest.raises(SceneError) as info:
        scene_from_dict(apply_overrides(BASE, {"projectile.nose": {"shape": "profile", "points": points}}))
    message = str(info.value)
    assert expected in message and "\n" not in message
