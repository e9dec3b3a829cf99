"""DAFL loads against closed forms and 1-D integrals, and their invariants."""

import functools
import math

import numpy as np
import pytest
from scipy import integrate
from support import meshed, slow_except

from cases.reference.normal_impact import embedded_axial_force
from fem_loads import DAFLLoads, resistance_law, surface_quadrature
from fem_loads.mass import mass_properties
from mesh import BODY, ConeNose, OgiveNose, Profile, ProjectileGeometry

SOIL = resistance_law("soil")
DOWN = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])  # body x -> world -Z
DEEP = np.array([0.0, 0.0, -10.0])


@functools.cache
def _loads(profile, size=0.01, model="exact", order=2, law=SOIL):
    mesh = meshed(ProjectileGeometry(profile), size, order)
    centre = mass_properties(mesh, {BODY: 1.0}).centre
    return DAFLLoads(surface_quadrature(mesh, centre, profile, model), law), -centre[0]


PROFILES = {
    "paper CRH 5": Profile(0.155, 0.93, OgiveNose(5.0)),
    "Forrestal-Luk CRH 3": Profile(0.0952, 1.4, OgiveNose(3.0)),
    "cone 12.92 deg": Profile(0.155, 0.93, ConeNose(12.92)),
}


@pytest.mark.parametrize("name", slow_except(PROFILES, "paper CRH 5"))
@pytest.mark.parametrize("speed", [100.0, 300.0, 1200.0])
def test_embedded_axial_force_matches_closed_form(name, speed):
    profile = PROFILES[name]
    loads, _ = _loads(profile)
    force, moment = loads(DEEP, np.array([0.0, 0.0, -speed]), DOWN, np.zeros(3))
    exact = embedded_axial_force(profile, SOIL, speed)
    assert force[2] == pytest.approx(exact, rel=5e-3)
    # axial motion of a mirror-symmetric quadrature: no side force, no moment, exactly (fem_loads.images)
    assert not force[:2].any() and not moment.any()


def test_tail_first_motion_loads_only_the_tail():
    profile = PROFILES["paper CRH 5"]
    loads, _ = _loads(profile)
    force, _ = loads(DEEP, np.array([0.0, 0.0, 200.0]), DOWN, np.zeros(3))
    exact = math.pi * profile.radius**2 * (SOIL.c0 + SOIL.c2 * 200.0**2)
    assert -force[2] == pytest.approx(exact, rel=1e-6)


def test_nothing_outside_the_target():
    loads, _ = _loads(PROFILES["paper CRH 5"], size=0.03)
    force, moment = loads(np.array([0.0, 0.0, 2.0]), np.array([0.0, 0.0, -500.0]), DOWN, np.zeros(3))
    assert not force.any() and not moment.any()


def test_lateral_motion_matches_1d_integrals():
    """Velocity V along body y, fully embedded, no rotation.

    With n = (n_f, n_r cos t, n_r sin t), Vn = V n_r cos t and the element area
    r sqrt(1 + r'^2) ds dt, the t-integrals are closed forms and
    F_y = -int r C ds, F_x = -int r r' D ds,
    M_z = -int (x r - r^2 r') C ds, with C = 2 A s0 + (4/3) B r0 V^2 n_r^2,
    D = pi A s0 + (pi/2) B r0 V^2 n_r^2 and x = Lc - s the forward coordinate.
    """
    profile = PROFILES["paper CRH 5"]
    loads, lc = _loads(profile)
    v = 150.0
    rotation = np.eye(3)  # any attitude: the whole body is deep inside
    force, moment = loads(DEEP, np.array([0.0, v, 0.0]), rotation, np.zeros(3))
    a_s0, b_r0 = SOIL.c0, SOIL.c2

    def parts(s):
        r, slope = float(profile.radius_at(s)), float(profile.slope_at(s))
        n_r2 = 1.0 / (1.0 + slope**2)
        c = 2 * a_s0 + 4 / 3 * b_r0 * v**2 * n_r2
        d = math.pi * a_s0 + math.pi / 2 * b_r0 * v**2 * n_r2
        return r, slope, c, d

    def quad(f):
        pts = [profile.nose_length]
        return integrate.quad(f, 0, profile.length, points=pts, epsrel=1e-12, limit=400)[0]

    f_y = -quad(lambda s: parts(s)[0] * parts(s)[2])
    f_x = -quad(lambda s: parts(s)[0] * parts(s)[1] * parts(s)[3])
    m_z = -quad(lambda s: ((lc - s) * parts(s)[0] - parts(s)[0] ** 2 * parts(s)[1]) * parts(s)[2])
    assert force[1] == pytest.approx(f_y, rel=5e-3)
    assert force[0] == pytest.approx(f_x, rel=5e-3)
    assert moment[2] == pytest.approx(m_z, rel=5e-3, abs=5e-3 * abs(f_y) * profile.length)
    assert abs(force[2]) < 1e-9 * abs(f_y) and np.abs(moment[:2]).max() < 1e-9 * abs(m_z)


def _random_states(n, seed=1):
    rng = np.random.default_rng(seed)
    for _ in range(n):
        q, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        q *= np.sign(np.linalg.det(q))
        yield (np.array([0.0, 0.0, rng.uniform(-1.0, 0.3)]), rng.normal(size=3) * 300, q, rng.normal(size=3) * 50)


def test_loads_never_do_positive_work():
    """Power F.V + M.omega = -sum sigma Vn dS <= 0: resistance only dissipates."""
    loads, _ = _loads(PROFILES["paper CRH 5"], size=0.02)
    for position, velocity, rotation, omega in _random_states(50):
        force, moment = loads(position, velocity, rotation, omega)
        assert force @ velocity + moment @ omega <= 1e-12 * np.linalg.norm(force) * np.linalg.norm(velocity)


def test_rotating_about_the_target_normal_rotates_the_force():
    loads, _ = _loads(PROFILES["paper CRH 5"], size=0.02)
    angle = 0.7
    spin = np.array([[math.cos(angle), -math.sin(angle), 0], [math.sin(angle), math.cos(angle), 0], [0, 0, 1]])
    for position, velocity, rotation, omega in _random_states(10, seed=2):
        force, moment = loads(position, velocity, rotation, omega)
        force2, moment2 = loads(spin @ position, spin @ velocity, spin @ rotation, omega)
        np.testing.assert_allclose(force2, spin @ force, rtol=1e-9, atol=1e-9 * np.abs(force).max())
        np.testing.assert_allclose(moment2, moment, rtol=1e-9, atol=1e-9 * np.abs(moment).max())
