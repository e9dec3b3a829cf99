"""Nose shapes: meshed against analytic volume and area, loads against their nose factors."""

import functools

import numpy as np
import pytest

from cases import load_scene, run_scene, scene_path, summarise
from cases.studies.reference import axial_depth_1d, embedded_axial_force
from fem_loads import DAFLLoads, mass_properties, resistance_law, surface_quadrature
from mesh import (BODY, BluntOgiveNose, ConeNose, OgiveNose, Profile, ProjectileGeometry, SecantOgiveNose,
                  analytic_mass_properties)
from support import meshed

NOSES = {
    "tangent ogive CRH 5": OgiveNose(5.0),
    "secant ogive CRH 8, 2 calibres": SecantOgiveNose(8.0, 2.0),
    "hemisphere": OgiveNose(0.5),
    "blunt CRH 3, 20 mm flat": BluntOgiveNose(3.0, 0.02),
    "cone 20 deg": ConeNose(20.0),
}
SOIL = resistance_law("soil")
DOWN = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])


@functools.lru_cache(maxsize=None)
def _meshed(name):
    profile = Profile(0.155, 0.93, NOSES[name])
    mesh = meshed(ProjectileGeometry(profile), 0.01, 2)
    mass = mass_properties(mesh, {BODY: 1.0})
    return profile, mesh, mass


@pytest.mark.parametrize("name", NOSES)
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


@pytest.mark.parametrize("name", NOSES)
@pytest.mark.parametrize("friction", [0.0, 0.1])
def test_embedded_axial_force_matches_the_nose_factors(name, friction):
    from fem_loads.target import Friction

    profile, mesh, mass = _meshed(name)
    loads = DAFLLoads(surface_quadrature(mesh, mass.centre, profile, "exact"), SOIL,
                      friction=Friction(friction) if friction else None)
    force, _ = loads(np.array([0.0, 0.0, -10.0]), np.array([0.0, 0.0, -500.0]), DOWN, np.zeros(3))
    assert force[2] == pytest.approx(embedded_axial_force(profile, SOIL, 500.0, friction), rel=5e-3)


def test_blunt_normal_impact_matches_the_1d_integration():
    scene = load_scene(scene_path("forrestal_luk_test2"),
                       {"projectile.nose": {"shape": "blunt", "crh": 3.0, "flat_radius": 0.01}})
    result = run_scene(scene)
    reference, _ = axial_depth_1d(result.prepared.profile, scene.target.build(),
                                  result.prepared.mass.mass, 280.0, scene.numerics.stop_speed,
                                  **scene.effects.contact)
    assert summarise(result).depth == pytest.approx(reference, rel=1e-3)
