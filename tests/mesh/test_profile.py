"""The analytic profile against closed forms, and the counterweight placement."""

import math

import numpy as np
import pytest
from scipy import integrate

from mesh import (
    ConeNose,
    Interior,
    OgiveNose,
    Profile,
    ProjectileGeometry,
    analytic_mass_properties,
    place_counterweight,
)


def test_ogive_nose_length_and_area_closed_form():
    p = Profile(0.155, 0.93, OgiveNose(5.0))
    big_r, a = 5 * 0.155, 0.0775
    ln = math.sqrt(big_r**2 - (big_r - a) ** 2)
    assert p.nose_length == pytest.approx(ln, rel=1e-15)
    nose_area = 2 * math.pi * big_r * (ln - (big_r - a) * math.asin(ln / big_r))
    exact = nose_area + 2 * math.pi * a * (0.93 - ln) + math.pi * a * a
    assert p.surface_area() == pytest.approx(exact, rel=1e-12)


def test_hemisphere_is_crh_one_half():
    p = Profile(0.1, 0.3, OgiveNose(0.5))
    assert p.nose_length == pytest.approx(0.05)
    s = np.linspace(0, 0.05, 11)
    assert np.allclose(p.radius_at(s), np.sqrt(0.05**2 - (0.05 - s) ** 2))


@pytest.mark.parametrize("nose", [OgiveNose(0.5), OgiveNose(3.0), OgiveNose(20.0), ConeNose(12.92), ConeNose(60.0)])
def test_nose_factor_is_the_integral_of_sin_cubed(nose):
    """N = (1/(pi a^2)) int 2 pi r r' sin^2(slope) ds over the nose (brief section 5)."""
    p = Profile(0.1, 1.0, nose)

    def integrand(s):
        slope = float(p.slope_at(s))
        return 2 * math.pi * float(p.radius_at(s)) * slope**3 / (1 + slope**2)

    value = integrate.quad(integrand, 0, p.nose_length, epsrel=1e-12, limit=200)[0]
    assert value / (math.pi * p.radius**2) == pytest.approx(p.nose_factor(), rel=1e-9)


def test_normals_are_unit_and_face_forward_on_the_nose():
    p = Profile(0.1, 1.0, OgiveNose(3.0))
    s = np.linspace(0, 1.0, 101)
    forward, radial = p.outward_normal(s)
    assert np.allclose(forward**2 + radial**2, 1.0)
    assert np.all(forward[s < p.nose_length] > 0) and np.all(forward[s > p.nose_length] == 0)


@pytest.mark.parametrize(
    "ratio, span",
    [(0.4448, (0.217, 0.400)), (0.5042, (0.328, 0.501)), (0.5636, (0.414, 0.586)), (0.6230, (0.516, 0.688))],
)
def test_placement_gives_mass_and_centre(ratio, span):
    p = Profile(0.155, 0.93, OgiveNose(5.0))
    interior = Interior(0.01, 0.02)
    x1, x2 = place_counterweight(p, interior, 7850, 18000, 75.67, ratio * 0.93)
    props = analytic_mass_properties(ProjectileGeometry(p, interior, (x1, x2)), 7850, 18000)
    assert props.mass == pytest.approx(75.67, rel=1e-10)
    assert props.centre_from_tip == pytest.approx(ratio * 0.93, rel=1e-10)
    # the brief quotes the spans "roughly" (its centres are rounded to 1 cm)
    assert x1 == pytest.approx(span[0], abs=0.012) and x2 == pytest.approx(span[1], abs=0.012)


def test_placement_out_of_reach_is_a_clear_error():
    p = Profile(0.155, 0.93, OgiveNose(5.0))
    with pytest.raises(ValueError, match="centre_of_mass = 0.1 m"):
        place_counterweight(p, Interior(0.01, 0.02), 7850, 18000, 75.67, 0.1)
    with pytest.raises(ValueError, match="mass = 500"):
        place_counterweight(p, Interior(0.01, 0.02), 7850, 18000, 500.0, 0.5)


def test_geometry_rejects_bad_interiors():
    p = Profile(0.155, 0.93, OgiveNose(5.0))
    with pytest.raises(ValueError, match="wall_thickness"):
        ProjectileGeometry(p, Interior(0.1, 0.02))
    with pytest.raises(ValueError, match="counterweight"):
        ProjectileGeometry(p, Interior(0.01, 0.02), (0.5, 2.0))
    with pytest.raises(ValueError, match="length"):
        Profile(0.155, 0.2, OgiveNose(5.0))
