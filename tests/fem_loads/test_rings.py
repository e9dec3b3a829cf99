"""The ring-by-ring DAFL of a body of revolution (fem_loads.kernels.rings) against the mesh's DAFL and closed forms."""

import functools
import math
from pathlib import Path

import numpy as np
import pytest
from support import meshed, ring_records, slow_except

import cases
from cases.reference.normal_impact import embedded_axial_force
from fem_loads import DAFLLoads, ResistanceLaw, mass_properties, resistance_law, surface_quadrature
from fem_loads.kernels.rings import PitchPlaneLoad, lowest_height, revolved_surface
from fem_loads.target import Friction
from fem_loads.user_law import user_law
from mesh import BODY, BluntOgiveNose, ConeNose, OgiveNose, Profile, ProjectileGeometry, analytic_mass_properties

SOIL = resistance_law("soil")
PAPER = Profile(0.155, 0.93, OgiveNose(5.0))
DELTA, ENTRY = 0.005, 0.01  # the default contact incidence; an entry ramp of 1 cm


def rotation(theta: float) -> np.ndarray:
    """Body to world, turned by ``theta`` about the world Y axis (fem_loads.kernels.rings's convention)."""
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, 0.0, s], [0.0, 1.0, 0.0], [-s, 0.0, c]])


@functools.cache
def _quadrature():
    """The paper's body at 10 mm (the mesh test_dafl and test_effects use), its quadrature and the tip's place."""
    mesh = meshed(ProjectileGeometry(PAPER), 0.01, 2)
    centre = mass_properties(mesh, {BODY: 1.0}).centre
    return surface_quadrature(mesh, centre, PAPER, "exact"), -float(centre[0])


@functools.cache
def _mesh_case(friction: Friction | None, law=SOIL, contact: str = "one_sided"):
    """The DAFL of the paper's body at 10 mm with ``law`` and ``friction``, and the tip's place."""
    quadrature, tip = _quadrature()
    entry_smoothing = ENTRY / math.sqrt(float(np.median(quadrature.weights)))
    loads = DAFLLoads(
        quadrature, law, friction=friction, contact_incidence=DELTA, contact=contact, entry_smoothing=entry_smoothing
    )
    return loads, tip


def _rings(
    friction: Friction | None, tip: float, entry: float = ENTRY, law=SOIL, contact: str = "one_sided", **counts
) -> PitchPlaneLoad:
    surface = revolved_surface(PAPER, tip, **counts)
    return PitchPlaneLoad(
        surface,
        ring_records(law, contact_incidence=DELTA, entry_length=entry, max_radius=surface.max_radius, friction=friction,
                 contact=contact),
    )  # fmt: skip


# height of the centre (m), axis tilt from straight down (deg), speed (m/s), attack (deg), pitch rate (rad/s)
STATES = {
    "embedded, axial": (-5.0, 0.0, 800.0, 0.0, 0.0),
    "embedded, 5 deg attack": (-5.0, 0.0, 800.0, 5.0, 0.0),
    "embedded, turning": (-5.0, 30.0, 600.0, 15.0, -180.0),
    "embedded, slow, nearly straight": (-5.0, 0.0, 300.0, 0.05, 0.5),
    "nose entering, tilted": (0.3, 10.0, 1000.0, 1.0, -20.0),
    "half in, 30 deg oblique": (0.05, 30.0, 900.0, 3.0, 40.0),
}
FRICTIONS = {"none": None, "Coulomb 0.1": Friction(0.1), "capped 10 MPa": Friction(0.1, 10e6)}


@pytest.mark.parametrize("friction", slow_except(list(FRICTIONS), "none", "Coulomb 0.1"))
@pytest.mark.parametrize("state", STATES)
def test_the_ring_load_is_the_mesh_load(state, friction):
    """The same law, ramps and friction over the exact surface and over the 10 mm mesh's quadrature agree
    within the mesh's own error: 0.3 % of the force's size in every component, and of its size times the
    length in the moment (measured at most 0.1 %).  Wholly embedded with the reduced model's 24 rings;
    partly embedded with 96 on the nose and 48 on the shank, since the waterline cuts the rings'
    integrand along the axis (24 rings err there by up to 6 % in the side force, docs/theory.md)."""
    _compare_with_mesh(state, FRICTIONS[friction])


LAWS = {
    "polynomial": ResistanceLaw(3e6, 900.0, c1=2.5e4),
    "power": ResistanceLaw(4e6, 0.0, c=5e3, n=1.6),
    "depth gradient": ResistanceLaw(1e7, 2e3, k=3e6),
    "user law": user_law(
        f"{Path(cases.__file__).parent}/laws/soil_laws.py:overburden",
        {"c0": 1e7, "c2": 2e3, "unit_weight": 1.8e4, "lateral_ratio": 0.5},
    ),
}


@pytest.mark.parametrize("contact", ["one_sided", "centred"])
@pytest.mark.parametrize("law", list(LAWS))
@pytest.mark.parametrize("state", ["embedded, turning", "nose entering, tilted"])
def test_the_ring_load_is_the_mesh_load_for_every_law_and_contact(state, law, contact):
    """Every law family and a user's law, either contact ramp: the same agreement as the shipped law's."""
    _compare_with_mesh(state, Friction(0.1), LAWS[law], contact)


def _compare_with_mesh(state: str, friction: Friction | None, law=SOIL, contact: str = "one_sided") -> None:
    loads, tip = _mesh_case(friction, law, contact)
    counts = {} if STATES[state][0] < -1.0 else {"nose_rings": 96, "shank_rings": 48}
    height, tilt, speed, attack, q = STATES[state]
    theta = math.radians(90.0 - tilt)  # 90 deg: the axis straight down
    velocity_body = speed * np.array([math.cos(math.radians(attack)), 0.0, math.sin(math.radians(attack))])
    world = rotation(theta)
    force, moment = loads(np.array([0.0, 0.0, height]), world @ velocity_body, world, np.array([0.0, q, 0.0]))
    force = world.T @ force
    rings = _rings(friction, tip, law=law, contact=contact, **counts)(height, theta, velocity_body[[0, 2]], q)
    size = float(np.hypot(force[0], force[2]))
    assert size > 1e4
    assert abs(rings[0] - force[0]) < 3e-3 * size
    assert abs(rings[1] - force[2]) < 3e-3 * size
    assert abs(rings[2] - moment[1]) < 3e-3 * size * PAPER.length


def test_closed_form_arcs_are_the_integrals():
    """Without friction the full-law arcs are closed forms; an infinitesimal friction coefficient sends every
    arc through Gauss-Legendre panels instead (6 points per 45 degrees), which integrate the same
    polynomials in ``cos phi`` to 1e-9.  Sharp switches (no ramp arcs, which both paths integrate by Gauss),
    random states, partly embedded ones included."""
    surface = revolved_surface(PAPER, 0.5, nose_rings=16, shank_rings=8)

    def load(mu):
        return PitchPlaneLoad(
            surface, ring_records(SOIL, max_radius=surface.max_radius, friction=Friction(mu) if mu else None)
        )

    exact, gauss = load(0.0), load(1e-300)
    rng = np.random.default_rng(7)
    for _ in range(200):
        height, theta = rng.uniform(-1.5, 0.5), math.radians(rng.uniform(45.0, 135.0))
        speed, attack, q = rng.uniform(50.0, 1500.0), math.radians(rng.uniform(-30.0, 30.0)), rng.uniform(-300, 300)
        velocity = speed * np.array([math.cos(attack), math.sin(attack)])
        a, b = exact(height, theta, velocity, q), gauss(height, theta, velocity, q)
        assert np.allclose(a, b, rtol=0.0, atol=1e-9 * (abs(a[:2]).max() + 1.0)), (a, b)


def _brute_force_rings(surface, law, friction, state, points=100_000):
    """The ring load by the midpoint rule in ``phi`` on ``points`` points per half ring: the integrand of the points'
    pipeline (the numpy path's scalar functions), summed as :func:`~fem_loads.kernels.rings.pitch_plane_load` sums
    it."""
    from fem_loads.factors import Switches, friction_stress_scalars, point_stress_scalars
    from fem_loads.target import slip_factor_scalars

    height, theta, (vx, vz), q = state
    width = DELTA * (math.hypot(vx, vz) + abs(q) * surface.max_radius)
    switches = Switches(True, True, 1.0 / width, 0.0, 0.0, False, 0.0, 1.0, True, math.inf, True, True)
    phi = (np.arange(points) + 0.5) * math.pi / points
    c, s = np.cos(phi), np.sin(phi)
    load = np.zeros(3)
    for x, rho, n_axial, n_radial, w in surface.rings:
        vn = n_axial * vx + (n_radial * vz + q * (rho * n_axial - x * n_radial)) * c
        h = height - math.sin(theta) * x + math.cos(theta) * rho * c
        sigma = point_stress_scalars(law.normal_stress(np.maximum(vn, 0.0), -h), vn, -h, h, 1.0 / ENTRY, switches)
        j0, j1, jx, jz, jm = (sigma.sum(), (sigma * c).sum(), 0.0, 0.0, 0.0)
        if friction is not None:
            sx, sy, sz = vx + q * rho * c - vn * n_axial, -vn * n_radial * s, vz - q * x - vn * n_radial * c
            slip = slip_factor_scalars(sx * sx + sy * sy + sz * sz, width, vx * vx + vz * vz)
            t = friction_stress_scalars(sigma, friction.coefficient, friction.cap or 0.0) * slip
            jx, jz, jm = (t * sx).sum(), (t * sz).sum(), (t * (rho * c * sx - x * sz)).sum()
        step = math.pi / points
        load -= (
            2.0 * w * step * np.array([n_axial * j0 + jx, n_radial * j1 + jz, (rho * n_axial - x * n_radial) * j1 + jm])
        )
    return load


@pytest.mark.parametrize("friction", [None, Friction(0.1), Friction(0.1, 5e6)], ids=["none", "Coulomb", "capped"])
@pytest.mark.parametrize(
    ("state", "tolerance"),
    [((-1.0, 80.0, (600.0, 40.0), 30.0), 1e-8), ((0.2, 70.0, (800.0, 100.0), -50.0), 1e-6)],
    ids=["embedded", "entering"],
)
def test_the_ring_load_is_its_integral(friction, state, tolerance):
    """Each ring's arcs, split where the load switches (the ramps' ends and, for the law ``c0 + c2 Vn^2``, the
    friction cap's kink), integrate the points' pipeline: against the midpoint rule on 100 000 points per half ring,
    to 1e-8 of the load deep in the target (a contact ramp's arc by 4 Gauss points per 45 degrees errs by 4e-9;
    an arc across the cap's kink, were it not split there, by 1e-6), and to 1e-6 with the nose entering (the
    entry ramp's arcs, 4e-7)."""
    surface = revolved_surface(PAPER, 0.5, nose_rings=16, shank_rings=8)
    records = ring_records(SOIL, contact_incidence=DELTA, entry_length=ENTRY, max_radius=surface.max_radius,
                       friction=friction)  # fmt: skip
    height, tilt, velocity, q = state
    state = (height, math.radians(tilt), velocity, q)
    rings = PitchPlaneLoad(surface, records)(*state)
    exact = _brute_force_rings(surface, SOIL, friction, state)
    assert np.abs(rings - exact).max() < tolerance * np.abs(exact[:2]).max(), (rings, exact)


@pytest.mark.parametrize("nose", [OgiveNose(5.0), ConeNose(12.92), BluntOgiveNose(3.0, 0.02)], ids=str)
def test_rings_carry_the_exact_area_and_volume(nose):
    profile = Profile(0.155, 0.93, nose)
    surface = revolved_surface(profile, 0.5, nose_rings=24, shank_rings=8)
    assert surface.area == pytest.approx(profile.surface_area(), rel=1e-9)
    volume = analytic_mass_properties(ProjectileGeometry(profile), 1.0).volume
    assert surface.enclosed_volume() == pytest.approx(volume, rel=1e-9)


@pytest.mark.parametrize("speed", [100.0, 1200.0])
def test_axial_force_is_the_closed_form(speed):
    """Axial motion, wholly embedded, sharp switches: ``pi a^2 (A sigma_0 + N B rho_0 V^2)`` (the nose factor)."""
    surface = revolved_surface(PAPER, 0.5)
    law = ring_records(SOIL, max_radius=surface.max_radius)
    fx, fz, my = PitchPlaneLoad(surface, law)(-5.0, math.pi / 2, (speed, 0.0), 0.0)
    assert -fx == pytest.approx(embedded_axial_force(PAPER, SOIL, speed), rel=1e-9)
    assert fz == 0.0 and my == 0.0


def test_a_mirrored_state_gives_the_mirrored_load():
    """The mirror image in the world plane X = 0 turns the axis to ``pi - theta`` and flips ``v_z`` and ``q``:
    the load's ``F_z`` and ``M_y`` flip, ``F_x`` stays (embedded, and entering at a tilt, with friction)."""
    load = _rings(Friction(0.1), 0.5)
    for height, theta, v, q in ((-5.0, 1.2, (700.0, 40.0), 35.0), (0.2, 1.4, (900.0, 12.0), -8.0)):
        fx, fz, my = load(height, theta, v, q)
        assert abs(fz) > 1e3 and abs(my) > 1e2
        mirrored = load(height, math.pi - theta, (v[0], -v[1]), -q)
        assert mirrored == pytest.approx((fx, -fz, -my), rel=1e-12, abs=1e-6)


def test_outside_the_target_and_moving_away_nothing():
    load = _rings(None, 0.5)
    assert not load(2.0, math.pi / 2, (800.0, 10.0), 5.0).any()  # above the surface
    assert not load(-5.0, math.pi / 2, (-800.0, 0.0), 0.0)[1:].any()  # tail first: the tail face only, no side load
    surface = revolved_surface(PAPER, 0.5)
    assert lowest_height(surface.outline, 0.0, 1.0, 0.0) == -0.5  # straight down: the tip
    assert lowest_height(surface.outline, 0.0, -1.0, 0.0) == pytest.approx(-0.43, abs=1e-12)  # up: the tail face
    tilted = math.radians(60.0)  # 30 degrees from the vertical: the tip, not the shoulder, is lowest
    assert lowest_height(surface.outline, 0.0, math.sin(tilted), math.cos(tilted)) == pytest.approx(
        -0.5 * math.sin(tilted)
    )
