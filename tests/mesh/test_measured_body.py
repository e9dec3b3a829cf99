"""A body behind the nose given as measured points (a boat tail, a flare): the profile, its mesh and mass
properties against 1-D integrals, its load against the exact integral, its runs, and bad tables."""

import math

import numpy as np
import pytest
from scipy import integrate
from support import meshed, ring_records, slow_except

from cases import load_scene, run_scene, scene_path, summarise
from cases.reference.normal_impact import axial_depth_1d, check_nose_alone_presses, embedded_axial_force
from cases.scene import SceneError
from fem_loads import DAFLLoads, mass_properties, resistance_law, surface_quadrature
from fem_loads.kernels.rings import PitchPlaneLoad, revolved_surface
from mesh import (
    BODY,
    Interior,
    OgiveNose,
    Profile,
    ProfileBody,
    ProjectileGeometry,
    analytic_mass_properties,
    place_counterweight,
)

SOIL = resistance_law("soil")
A = 0.0775  # m: the 155 mm family's shank radius
BOAT_TAIL = Profile(0.155, 0.93, OgiveNose(5.0), ProfileBody(((0.75, A), (0.85, 0.073), (0.93, 0.062))))
FLARE = Profile(0.155, 0.93, OgiveNose(5.0), ProfileBody(((0.70, A), (0.82, 0.082), (0.93, 0.095))))
DOWN = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # body x -> world -Z


def test_the_body_joins_the_shank_and_ends_at_the_tail():
    p = BOAT_TAIL
    assert float(p.radius_at(0.6)) == A and float(p.slope_at(0.6)) == 0.0  # the cylinder before the body
    np.testing.assert_allclose(p.radius_at(np.array([0.75, 0.85, 0.93])), [A, 0.073, 0.062], rtol=0, atol=1e-15)
    assert p.tail_radius == 0.062 and p.largest_radius == A and FLARE.largest_radius == 0.095
    assert 0.75 in p.breakpoints and 0.85 in p.breakpoints and 0.93 not in p.breakpoints
    s = np.linspace(0.75, 0.93, 1001)
    assert np.all(np.diff(p.radius_at(s)) <= 0.0)  # a narrowing table gives a narrowing body (no overshoot)
    lateral = integrate.quad(
        lambda s: 2 * math.pi * float(p.radius_at(s)) * math.hypot(1, float(p.slope_at(s))),
        0,
        0.93,
        points=p.breakpoints,
        limit=200,
        epsrel=1e-12,
    )[0]
    assert p.surface_area() == pytest.approx(lateral + math.pi * 0.062**2, rel=1e-10)


@pytest.mark.parametrize(
    "points, message",
    [
        (((0.75, A),), r"at least 2"),
        (((0.75, A), (0.74, 0.07), (0.93, 0.06)), r"body.points\[1\].*x strictly increasing"),
        (((0.75, A), (0.85, 0.0), (0.93, 0.06)), r"body.points\[1\].*r must be > 0"),
        (((0.75, 0.07), (0.93, 0.06)), r"body.points\[0\].*shank radius"),
        (((0.2, A), (0.93, 0.06)), r"body.points\[0\].*lies on the nose"),
        (((0.75, A), (0.9, 0.06)), r"body.points\[1\].*must be the tail"),
    ],
)
def test_bad_tables_say_which_point_and_what_is_allowed(points, message):
    with pytest.raises(ValueError, match=message):
        Profile(0.155, 0.93, OgiveNose(5.0), ProfileBody(points))


@pytest.mark.parametrize("profile", [BOAT_TAIL, FLARE], ids=["boat tail", "flare"])
def test_meshed_body_matches_its_1d_integrals(profile):
    """20 mm, quadratic: volume and centre of the mesh, and the surface quadrature's area and enclosed volume
    (exact normals and the mesh's own), against the profile's 1-D integrals within 1e-4."""
    mesh = meshed(ProjectileGeometry(profile), 0.02, 2)
    mass = mass_properties(mesh, {BODY: 1.0})
    exact = analytic_mass_properties(ProjectileGeometry(profile), 1.0)
    assert mass.volume == pytest.approx(exact.volume, rel=1e-4)
    assert mass.centre_from_tip == pytest.approx(exact.centre_from_tip, rel=1e-4)
    assert mass.transverse_inertia == pytest.approx(exact.transverse_inertia, rel=1e-4)
    for model in ("exact", "mesh"):
        q = surface_quadrature(mesh, mass.centre, profile, model)
        assert q.area == pytest.approx(profile.surface_area(), rel=1e-4)
        assert q.enclosed_volume() == pytest.approx(exact.volume, rel=1e-4)


def test_a_boat_tail_with_a_cavity_and_counterweight_keeps_the_mass_and_centre():
    """#3's stand-in interior (10 mm wall, 20 mm tail plate) inside a boat-tailed body, the counterweight placed for
    75.67 kg at Lc/L = 56.36 %: the mesh's mass and centre within 1e-4 of the targets; a wall thicker than the
    narrowest radius is refused."""
    interior = Interior(0.01, 0.02)
    span = place_counterweight(BOAT_TAIL, interior, 7850.0, 18000.0, 75.67, 0.5636 * 0.93)
    geometry = ProjectileGeometry(BOAT_TAIL, interior, span)
    mass = mass_properties(meshed(geometry, 0.02, 2), {BODY: 7850.0, 2: 18000.0})
    assert mass.mass == pytest.approx(75.67, rel=1e-4)
    assert mass.centre_from_tip == pytest.approx(0.5636 * 0.93, rel=1e-4)
    narrow = Profile(0.155, 0.93, OgiveNose(5.0), ProfileBody(((0.75, A), (0.93, 0.02))))
    with pytest.raises(ValueError, match="interior.wall_thickness.*narrowest radius"):
        ProjectileGeometry(narrow, Interior(0.03, 0.02))  # the body is 26 mm in radius at the tail plate


def _flare_axial_force(speed: float) -> float:
    """The nose's closed form plus the flare's exact integral: ``int 2 pi r r' (A sigma_0 + B rho_0 V^2 sin^2) ds``
    over the body, where it faces forward (``r' > 0``), and the tail disc is not loaded."""
    nose = embedded_axial_force(Profile(0.155, 0.93, OgiveNose(5.0)), SOIL, speed)

    def integrand(s: float) -> float:
        slope = float(FLARE.slope_at(s))
        sin2 = slope**2 / (1 + slope**2)
        return 2 * math.pi * float(FLARE.radius_at(s)) * max(slope, 0.0) * (SOIL.c0 + SOIL.c2 * speed**2 * sin2)

    flare = integrate.quad(integrand, FLARE.body.start, 0.93, points=FLARE.breakpoints, limit=200, epsrel=1e-12)[0]
    return nose + flare


@pytest.mark.parametrize("speed", slow_except([100.0, 800.0], 800.0))
@pytest.mark.slow  # seconds of runs: CI's slow step
def test_a_flare_presses_in_axial_motion(speed):
    """Fully embedded, axial, sharp switches: the mesh's DAFL (10 mm) within 5e-3 and the ring-by-ring load
    within 1e-6 of the nose's closed form plus the flare's exact integral; the 1-D references refuse a flare
    and take a boat tail."""
    exact = _flare_axial_force(speed)
    mesh = meshed(ProjectileGeometry(FLARE), 0.01, 2)
    centre = mass_properties(mesh, {BODY: 1.0}).centre
    loads = DAFLLoads(surface_quadrature(mesh, centre, FLARE, "exact"), SOIL)
    force, _ = loads(np.array([0.0, 0.0, -10.0]), np.array([0.0, 0.0, -speed]), DOWN, np.zeros(3))
    assert force[2] == pytest.approx(exact, rel=5e-3)
    surface = revolved_surface(FLARE, -float(centre[0]), nose_rings=24, shank_rings=24)
    rings = PitchPlaneLoad(surface, ring_records(SOIL, max_radius=surface.max_radius))
    assert -rings(-10.0, math.pi / 2, (speed, 0.0), 0.0)[0] == pytest.approx(exact, rel=1e-6)
    with pytest.raises(ValueError, match="flare"):
        check_nose_alone_presses(FLARE)
    check_nose_alone_presses(BOAT_TAIL)


def test_a_boat_tail_goes_as_deep_as_its_nose_says():
    """Test 2's projectile with a boat tail (its mass kept): in a straight normal impact the boat tail faces
    backward and never presses, so the depth is the 1-D reference's with the same nose and mass (within the
    20 mm mesh's 5e-4), and the same as the cylinder's."""
    body = {"points": [[1.2, 0.0476], [1.3, 0.045], [1.4, 0.04]]}
    scene = load_scene(scene_path("forrestal_luk_test2"), {"projectile.body": body})
    result = run_scene(scene)
    depth = summarise(result).depth
    reference, _ = axial_depth_1d(
        scene.projectile.profile(),
        scene.target.build(),
        result.prepared.mass.mass,
        scene.impact.speed,
        scene.stop_speed,
        **scene.effects.contact_ramp,
    )
    assert depth == pytest.approx(reference, rel=5e-4)
    cylinder = summarise(run_scene(load_scene(scene_path("forrestal_luk_test2")))).depth
    assert depth == pytest.approx(cylinder, rel=1e-6)


def test_a_body_is_for_analytic_projectiles_and_bad_points_are_one_line():
    with pytest.raises(SceneError, match=r"projectile.*body.*geometry file sets the shape"):
        load_scene(scene_path("eroded_test2"), {"projectile.body": {"points": [[1.2, 0.0476], [1.4, 0.04]]}})
    with pytest.raises(SceneError, match=r"body.points\[1\]") as error:
        load_scene(scene_path("forrestal_luk_test2"), {"projectile.body": {"points": [[1.2, 0.0476], [1.3, 0.04]]}})
    assert "\n" not in str(error.value)
