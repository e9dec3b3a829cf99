"""A nose given as measured points: the interpolant against the ogive it was sampled from, its exact
B-spline, bad tables."""

import math

import numpy as np
import pytest

from mesh import (
    Interior,
    OgiveNose,
    Profile,
    ProfileNose,
    ProjectileGeometry,
    analytic_mass_properties,
    place_counterweight,
)

DIAMETER, LENGTH = 0.0952, 1.4  # m: the validation projectile (Forrestal-Luk, CRH 3)
OGIVE = Profile(DIAMETER, LENGTH, OgiveNose(3.0))


def sampled(n: int, profile: Profile = OGIVE) -> tuple[tuple[float, float], ...]:
    """``n`` points of ``profile``'s nose, evenly spaced in x (m)."""
    x = np.linspace(0.0, profile.nose_length, n)
    r = profile.radius_at(x)
    r[-1] = profile.radius
    return tuple(zip(x.tolist(), r.tolist()))


def measured(n: int) -> Profile:
    return Profile(DIAMETER, LENGTH, ProfileNose(sampled(n)))


def test_the_interpolant_passes_through_the_points():
    p = measured(30)
    x, r = np.array(sampled(30)).T
    np.testing.assert_allclose(p.radius_at(x), r, rtol=0, atol=1e-15)
    assert p.nose_length == x[-1] and p.tip_radius == 0.0
    assert float(p.radius_at(LENGTH)) == p.radius and float(p.slope_at(0.5 * LENGTH)) == 0.0


# largest errors between the samples (radius / shank radius, slope): second order in the radius, first in the
# slope (measured: 8.1e-5 and 4.8e-3 with 30 points, 1.9e-5 and 2.3e-3 with 60)
@pytest.mark.parametrize("n, radius_error, slope_error", [(10, 1e-3, 2e-2), (30, 1e-4, 5e-3), (60, 2.5e-5, 2.5e-3)])
def test_radius_and_slope_between_the_samples_follow_the_ogive(n, radius_error, slope_error):
    p = measured(n)
    s = np.linspace(0.0, OGIVE.nose_length, 4001)
    assert np.abs(p.radius_at(s) - OGIVE.radius_at(s)).max() < radius_error * OGIVE.radius
    assert np.abs(p.slope_at(s) - OGIVE.slope_at(s)).max() < slope_error
    # the tip stays pointed with a finite angle; the shoulder meets the shank nearly tangentially
    assert float(p.slope_at(0.0)) == pytest.approx(float(OGIVE.slope_at(0.0)), rel=2 * slope_error)
    assert 0.0 <= float(p.slope_at(OGIVE.nose_length * (1 - 1e-12))) < slope_error


def test_slopes_are_continuous_and_normals_unit():
    p = measured(12)
    knots = np.array(sampled(12))[1:-1, 0]
    eps = 1e-9 * OGIVE.nose_length
    np.testing.assert_allclose(p.slope_at(knots - eps), p.slope_at(knots + eps), atol=1e-6)
    forward, radial = p.outward_normal(np.linspace(0, LENGTH, 301))
    np.testing.assert_allclose(forward**2 + radial**2, 1.0)


def test_one_dimensional_integrals_match_the_ogive():
    p = measured(30)
    exact, approx = (analytic_mass_properties(ProjectileGeometry(q), 7850.0) for q in (OGIVE, p))
    assert approx.volume == pytest.approx(exact.volume, rel=1e-7)
    assert approx.transverse_inertia == pytest.approx(exact.transverse_inertia, rel=1e-7)
    assert p.surface_area() == pytest.approx(OGIVE.surface_area(), rel=1e-7)
    assert p.nose_factor() == pytest.approx(OGIVE.nose_factor(), rel=2e-5)
    interior = Interior(0.01, 0.05)
    assert ProjectileGeometry(p, interior).cavity_start == pytest.approx(
        ProjectileGeometry(OGIVE, interior).cavity_start, rel=1e-5
    )


def test_counterweight_placement_works_on_a_measured_nose():
    p, interior = measured(30), Interior(0.01, 0.05)
    target = analytic_mass_properties(ProjectileGeometry(p, interior, (0.1, 0.5)), 7850.0, 18000.0)
    span = place_counterweight(p, interior, 7850.0, 18000.0, target.mass, target.centre_from_tip)
    np.testing.assert_allclose(span, (0.1, 0.5), rtol=1e-8)


def test_bezier_pieces_are_the_interpolant():
    """The mesher draws each cubic piece as a Bezier curve: its points lie on the interpolant."""
    p = measured(9)
    start, drop = 0.013, 0.004
    poles, knots, multiplicities = p.curve.bezier(start, drop)
    assert len(poles) == 3 * (len(knots) - 1) + 1 == sum(multiplicities) - 4
    t = np.linspace(0, 1, 7)[:, None]
    for k in range(len(knots) - 1):
        b = np.array(poles[3 * k : 3 * k + 4])
        curve = (1 - t) ** 3 * b[0] + 3 * (1 - t) ** 2 * t * b[1] + 3 * (1 - t) * t**2 * b[2] + t**3 * b[3]
        np.testing.assert_allclose(curve[:, 1] + drop, p.radius_at(curve[:, 0]), atol=1e-15)


BAD = {
    "fewer than 3": ([(0, 0), (0.1, 0.0476)], "at least 3"),
    "not at the tip": ([(0, 0.001), (0.05, 0.03), (0.1, 0.0476)], r"points\[0\].*must be the tip"),
    "not starting at x = 0": ([(0.01, 0), (0.05, 0.03), (0.1, 0.0476)], r"points\[0\].*must be the tip"),
    "x repeated": ([(0, 0), (0.05, 0.03), (0.05, 0.04), (0.1, 0.0476)], r"points\[2\].*x strictly increasing"),
    "x decreasing": ([(0, 0), (0.05, 0.03), (0.04, 0.04), (0.1, 0.0476)], r"points\[2\].*x strictly increasing"),
    "r decreasing": ([(0, 0), (0.05, 0.03), (0.07, 0.02), (0.1, 0.0476)], r"points\[2\].*r non-decreasing"),
    "nan": ([(0, 0), (0.05, math.nan), (0.1, 0.0476)], r"points\[1\].*finite"),
    "inf": ([(0, 0), (math.inf, 0.03), (0.1, 0.0476)], r"points\[1\].*finite"),
    "not pairs": ([(0, 0), (0.05,), (0.1, 0.0476)], "pairs of numbers"),
    "short of the shank": ([(0, 0), (0.05, 0.03), (0.1, 0.0470)], r"points\[2\].*shank radius.*0.0476"),
    "past the shank": ([(0, 0), (0.05, 0.03), (0.1, 0.0476 * (1 + 2e-6))], r"within 1e-06"),
}


@pytest.mark.parametrize("case", BAD)
def test_bad_tables_are_refused_naming_the_point(case):
    points, message = BAD[case]
    with pytest.raises(ValueError, match=message):
        Profile(DIAMETER, LENGTH, ProfileNose(points))


def test_the_last_radius_may_round_to_the_shank():
    points = [(0, 0), (0.05, 0.03), (0.1, 0.0476 * (1 + 5e-7))]
    p = Profile(DIAMETER, LENGTH, ProfileNose(points))
    assert float(p.radius_at(0.1)) == p.radius  # set to the shank radius exactly
