"""Nose shapes: meshed against analytic volume and area, loads against their nose factors."""

import functools

import numpy as np
import pytest
from support import meshed, slow_except

from cases import load_scene, run_scene, scene_path, summarise
from cases.reference.normal_impact import axial_depth_1d, embedded_axial_force
from fem_loads import DAFLLoads, mass_properties, resistance_law, surface_quadrature
from mesh import (
    BODY,
    BluntOgiveNose,
    ConeNose,
    OgiveNose,
    Profile,
    ProfileNose,
    ProjectileGeometry,
    SecantOgiveNose,
    analytic_mass_properties,
)


def sampled_ogive(crh: float, diameter: float, length: float, n: int) -> ProfileNose:
    """A measured nose of ``n`` points evenly spaced in x on the tangent ogive of ``crh`` (m)."""
    ogive = Profile(diameter, length, OgiveNose(crh))
    x = np.linspace(0.0, ogive.nose_length, n)
    r = ogive.radius_at(x)
    r[-1] = ogive.radius
    return ProfileNose(tuple(zip(x.tolist(), r.tolist())))


NOSES = {
    "tangent ogive CRH 5": OgiveNose(5.0),
    "secant ogive CRH 8, 2 calibres": SecantOgiveNose(8.0, 2.0),
    "hemisphere": OgiveNose(0.5),
    "blunt CRH 3, 20 mm flat": BluntOgiveNose(3.0, 0.02),
    "cone 20 deg": ConeNose(20.0),
}
SOIL = resistance_law("soil")
DOWN = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])


@functools.cache
def _meshed(name):
    profile = Profile(0.155, 0.93, NOSES[name])
    mesh = meshed(ProjectileGeometry(profile), 0.01, 2)
    mass = mass_properties(mesh, {BODY: 1.0})
    return profile, mesh, mass


@pytest.mark.parametrize("name", slow_except(NOSES, "tangent ogive CRH 5"))
def test_meshed_volume_and_area_match_the_profile(name):
    profile, mesh, mass = _meshed(name)
    exact = analytic_mass_properties(ProjectileGeometry(profile), 1.0)
    assert mass.volume == pytest.approx(exact.volume, rel=1e-4)
    assert mass.centre_from_tip == pytest.approx(exact.centre_from_tip, rel=1e-4)
    for model in ("mesh", "exact"):
        q = surface_quadrature(mesh, np.zeros(3), profile, model)
        assert q.area == pytest.approx(profile.surface_area(), rel=1e-4)
        assert q.enclosed_volume() == pytest.approx(exact.volume, rel=1e-4)


def test_secant_ogive_of_tangent_radius_is_the_tangent_ogive():
    tangent = Profile(0.155, 0.93, OgiveNose(5.0))
    secant = Profile(0.155, 0.93, SecantOgiveNose(5.0, tangent.nose_length / 0.155))
    s = np.linspace(0, 0.93, 50)
    np.testing.assert_allclose(secant.radius_at(s), tangent.radius_at(s), atol=1e-12)
    assert secant.nose_factor() == pytest.approx(tangent.nose_factor(), rel=1e-10)
    with pytest.raises(ValueError, match="needs crh >="):
        Profile(0.155, 0.93, SecantOgiveNose(2.0, 2.0))


@pytest.mark.parametrize("name", slow_except(NOSES, "tangent ogive CRH 5"))
@pytest.mark.parametrize("friction", [0.0, 0.1])
def test_embedded_axial_force_matches_the_nose_factors(name, friction):
    from fem_loads.target import Friction

    profile, mesh, mass = _meshed(name)
    loads = DAFLLoads(
        surface_quadrature(mesh, mass.centre, profile, "exact"), SOIL, friction=Friction(friction) if friction else None
    )
    force, _ = loads(np.array([0.0, 0.0, -10.0]), np.array([0.0, 0.0, -500.0]), DOWN, np.zeros(3))
    assert force[2] == pytest.approx(embedded_axial_force(profile, SOIL, 500.0, friction), rel=5e-3)


def test_meshed_profile_nose_matches_the_ogive_it_was_sampled_from():
    """30 points of test 2's CRH 3 ogive, meshed at the shipped 20 mm: volume, inertia and area within 2e-4 of
    the analytic ogive's (the 20 mm mesh's own error: 1.1e-4 in the inertia, for the ogive too) and within 1e-5
    of the meshed ogive's (the interpolant's own error is 1e-7 in these integrals); the embedded axial force."""
    ogive = Profile(0.0952, 1.4, OgiveNose(3.0))
    profile = Profile(0.0952, 1.4, sampled_ogive(3.0, 0.0952, 1.4, 30))
    exact = analytic_mass_properties(ProjectileGeometry(ogive), 1.0)
    (mesh, mass), (_, ogive_mass) = (
        (m, mass_properties(m, {BODY: 1.0})) for m in (meshed(ProjectileGeometry(p), 0.02, 2) for p in (profile, ogive))
    )
    for name in ("volume", "centre_from_tip", "axial_inertia", "transverse_inertia"):
        assert getattr(mass, name) == pytest.approx(getattr(exact, name), rel=2e-4), name
        assert getattr(mass, name) == pytest.approx(getattr(ogive_mass, name), rel=1e-5), name
    for model in ("mesh", "exact"):
        q = surface_quadrature(mesh, np.zeros(3), profile, model)
        assert q.area == pytest.approx(ogive.surface_area(), rel=2e-4)
        assert q.enclosed_volume() == pytest.approx(exact.volume, rel=2e-4)
    loads = DAFLLoads(surface_quadrature(mesh, mass.centre, profile, "exact"), SOIL)
    force, _ = loads(np.array([0.0, 0.0, -10.0]), np.array([0.0, 0.0, -500.0]), DOWN, np.zeros(3))
    assert force[2] == pytest.approx(embedded_axial_force(ogive, SOIL, 500.0), rel=5e-3)


def test_profile_nose_of_30_points_gives_the_ogive_depth():
    """The issue's acceptance: test 2 with its CRH 3 ogive given as 30 points, within 0.2 % in depth
    (measured: -3.0e-4 at the shipped 20 mm mesh; the 1-D reference alone: -1.0e-5)."""
    path = scene_path("forrestal_luk_test2")
    nose = sampled_ogive(3.0, 0.0952, 1.4, 30)
    table = {"projectile.nose": {"shape": "profile", "points": [list(p) for p in nose.points]}}
    depth, ogive = (summarise(run_scene(load_scene(path, extra))).depth for extra in (table, {}))
    assert depth == pytest.approx(ogive, rel=2e-3)


def test_blunt_normal_impact_matches_the_1d_integration():
    scene = load_scene(
        scene_path("forrestal_luk_test2"), {"projectile.nose": {"shape": "blunt", "crh": 3.0, "flat_radius": 0.01}}
    )
    result = run_scene(scene)
    reference, _ = axial_depth_1d(
        result.prepared.profile,
        scene.target.build(),
        result.prepared.mass.mass,
        280.0,
        scene.stop_speed,
        **scene.effects.contact_ramp,
    )
    assert summarise(result).depth == pytest.approx(reference, rel=1e-3)
