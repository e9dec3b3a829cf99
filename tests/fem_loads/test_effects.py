"""Optional effects: friction against its closed form, layers, free surface, gravity, separation."""

import functools
import math

import numpy as np
import pytest
from scipy import integrate
from support import meshed, slow_except

from cases import history_table, load_scene, run_scene, scene_path, summarise
from cases.reference.normal_impact import embedded_axial_force, nose_factors
from fem_loads import DAFLLoads, mass_properties, resistance_law, surface_quadrature
from fem_loads.resistance import ResistanceLaw
from fem_loads.target import FreeSurface, Friction, LayeredTarget
from mesh import BODY, ConeNose, OgiveNose, Profile, ProjectileGeometry

SOIL = resistance_law("soil")
DOWN = np.array([[0.0, 0.0, 1.0], [0.0, 1.0, 0.0], [-1.0, 0.0, 0.0]])
DEEP = np.array([0.0, 0.0, -10.0])
PROFILES = {
    "paper CRH 5": Profile(0.155, 0.93, OgiveNose(5.0)),
    "Forrestal-Luk CRH 3": Profile(0.0952, 1.4, OgiveNose(3.0)),
    "cone 12.92 deg": Profile(0.155, 0.93, ConeNose(12.92)),
}
COARSE = (("numerics.mesh_size", 0.02), ("numerics.quadrature_order", 2), ("numerics.integrator", "rk4"))


@functools.cache
def _quadrature(profile):
    mesh = meshed(ProjectileGeometry(profile), 0.01, 2)
    return surface_quadrature(mesh, mass_properties(mesh, {BODY: 1.0}).centre, profile, "exact")


@pytest.mark.parametrize("name", PROFILES)
def test_friction_nose_factors_are_the_integrals(name):
    profile, mu = PROFILES[name], 0.1
    a2 = math.pi * profile.radius**2

    def sin2(s):
        slope = float(profile.slope_at(s))
        return slope**2 / (1 + slope**2)

    side = integrate.quad(lambda s: 2 * math.pi * float(profile.radius_at(s)), 0, profile.nose_length)[0]
    dyn = integrate.quad(lambda s: 2 * math.pi * float(profile.radius_at(s)) * sin2(s), 0, profile.nose_length)[0]
    n1, n2 = nose_factors(profile, mu)
    assert n1 == pytest.approx(1 + mu * side / a2, rel=1e-10)
    assert n2 == pytest.approx(profile.nose_factor() + mu * dyn / a2, rel=1e-10)
    assert nose_factors(profile, 0.0) == pytest.approx((1.0, profile.nose_factor()), rel=1e-14)


@pytest.mark.parametrize("name", slow_except(PROFILES, "paper CRH 5"))
@pytest.mark.parametrize("speed", [100.0, 1200.0])
def test_coulomb_axial_force_matches_closed_form(name, speed):
    profile = PROFILES[name]
    loads = DAFLLoads(_quadrature(profile), SOIL, friction=Friction(0.1))
    force, moment = loads(DEEP, np.array([0.0, 0.0, -speed]), DOWN, np.zeros(3))
    exact = embedded_axial_force(profile, SOIL, speed, friction=0.1)
    assert force[2] == pytest.approx(exact, rel=5e-3)
    assert np.abs(force[:2]).max() < 1e-9 * exact and np.abs(moment).max() < 1e-9 * exact


def test_capped_friction_is_the_cap_times_the_sliding_area():
    """With a cap far below mu sigma, tau = tau_s everywhere loaded: drag = static part + tau_s int 2 pi r ds."""
    profile = PROFILES["paper CRH 5"]
    cap = 1.0e3
    frictionless = DAFLLoads(_quadrature(profile), SOIL)
    capped = DAFLLoads(_quadrature(profile), SOIL, friction=Friction(0.1, cap))
    args = (DEEP, np.array([0.0, 0.0, -300.0]), DOWN, np.zeros(3))
    extra = capped(*args)[0][2] - frictionless(*args)[0][2]
    side = integrate.quad(lambda s: 2 * math.pi * float(profile.radius_at(s)), 0, profile.nose_length)[0]
    assert extra == pytest.approx(cap * side, rel=5e-3)


def _thaw(value):
    """Tuples of pairs back to tables and tuples to arrays (the cache below needs hashable arguments)."""
    if (
        isinstance(value, tuple)
        and value
        and all(isinstance(v, tuple) and len(v) == 2 and isinstance(v[0], str) for v in value)
    ):
        return {k: _thaw(v) for k, v in value}
    return [_thaw(v) for v in value] if isinstance(value, tuple) else value


@functools.cache
def _run(name, *overrides):
    """Run a shipped scene with (key, value) overrides; a ``target.layers`` override replaces its law."""
    result = run_scene(load_scene(scene_path(name), [(k, _thaw(v)) for k, v in overrides]))
    return result, history_table(result)


STIFF = (("A", 5.0), ("sigma_0", 10.0e6), ("B", 3.0), ("rho_0", 1860.0))
SOFT_OVER_STIFF = ((("thickness", 2.0), ("law", "soil")), (("law", STIFF),))


@pytest.mark.slow  # 5 s; the Coulomb force's closed form stays in the default run
def test_friction_lowers_depth():
    plain = summarise(*_run("forrestal_luk_test2", *COARSE))
    rough = summarise(*_run("forrestal_luk_test2", *COARSE, ("effects.friction.model", "coulomb")))
    assert rough.depth < 0.9 * plain.depth


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_two_layers_of_one_law_are_the_homogeneous_target():
    one, _ = _run("forrestal_luk_test5", *COARSE)
    two, _ = _run(
        "forrestal_luk_test5", *COARSE, ("target.layers", ((("thickness", 2.0), ("law", "soil")), (("law", "soil"),)))
    )
    np.testing.assert_allclose(two.trajectory.position, one.trajectory.position, rtol=0, atol=1e-12)
    np.testing.assert_allclose(two.trajectory.velocity, one.trajectory.velocity, rtol=1e-13, atol=1e-10)


@pytest.mark.slow  # seconds of runs: CI's slow step
def test_a_stiffer_layer_decelerates_faster():
    soft, soft_h = _run("forrestal_luk_test2", *COARSE)
    layered, layered_h = _run("forrestal_luk_test2", *COARSE, ("target.layers", SOFT_OVER_STIFF))
    assert summarise(layered, layered_h).depth < summarise(soft, soft_h).depth
    # identical until the nose reaches the interface, then a larger deceleration
    before = soft_h["tip_depth"] < 1.9
    n = int(before.sum())
    np.testing.assert_allclose(layered_h["speed"][:n], soft_h["speed"][:n], rtol=1e-12)
    deceleration = lambda h: -np.gradient(h["speed"], h["time"])  # noqa: E731
    at = lambda h: int(np.searchsorted(h["tip_depth"], 2.5))  # noqa: E731
    assert deceleration(layered_h)[at(layered_h)] > 1.5 * deceleration(soft_h)[at(soft_h)]


@pytest.mark.slow
def test_crossing_into_a_stiffer_layer_at_an_angle_keeps_the_path():
    """At 30 degrees the lower flank of the nose meets the stiff layer first, but the path after the
    interface keeps its direction: the shank rides on its contact as on a rail.  The turn the stiff
    layer adds is a regularisation effect that falls with the contact incidence (20 mm, 3 points per
    facet, RK4: 0.032 deg at the default 0.005 and 2e-5 s, 0.015 at 0.0025, 0.011 at 0.0017 with
    1e-5 s; at 0.00125 the ramp is too stiff for 2e-5 s and chatters, 0.26). The sharp law seemed to
    turn the path away from the normal (0.24 deg at 2e-5 s), but its turn falls with the step
    (0.089 deg at 5e-6 s): the chatter of its switch, not physics."""

    def direction_after_interface(h):
        i = int(np.searchsorted(h["tip_depth"].to_numpy(), 2.0))
        dx = h["position_x"].iloc[-1] - h["position_x"].iloc[i]
        dz = h["position_z"].iloc[-1] - h["position_z"].iloc[i]
        return math.degrees(math.atan2(dx, -dz))  # from the downward normal

    def turn(*numerics):
        _, homogeneous = _run("forrestal_luk_test3", *COARSE, *numerics)
        _, crossing = _run("forrestal_luk_test3", *COARSE, *numerics, ("target.layers", SOFT_OVER_STIFF))
        return direction_after_interface(crossing) - direction_after_interface(homogeneous)

    default = turn()
    narrow = turn(("effects.contact_incidence", 0.005 / 3), ("numerics.time_step", 1e-5))
    assert 0.0 < default < 0.06 and 0.0 < narrow < 0.6 * default


@pytest.mark.slow  # the default suite keeps within 4 minutes on 2 cores; CI runs it
def test_free_surface_reduction_deepens_the_path():
    factor = FreeSurface(0.5, 0.2).factor(np.array([-1.0, 0.0, 0.25, 0.5, 2.0]))
    np.testing.assert_allclose(factor, [0.2, 0.2, 0.6, 1.0, 1.0])
    plain = summarise(*_run("forrestal_luk_test2", *COARSE))
    reduced = summarise(*_run("forrestal_luk_test2", *COARSE, ("effects.free_surface.depth", 0.5)))
    assert reduced.depth > plain.depth + 0.05


def test_gravity_adds_the_weight():
    plain, _ = _run("forrestal_luk_test2", *COARSE)
    heavy, _ = _run("forrestal_luk_test2", *COARSE, ("effects.gravity", True))
    mass = plain.prepared.mass.mass
    np.testing.assert_allclose(heavy.trajectory.force[0], plain.trajectory.force[0] + [0, 0, -9.80665 * mass])
    assert summarise(heavy).depth > summarise(plain).depth


def test_layers_pick_the_law_by_depth():
    target = LayeredTarget(
        (1.0, 2.0),
        (resistance_law("soil"), resistance_law("softer_soil"), resistance_law("soil_dynamic_cavity_expansion")),
    )
    static = target.normal_stress(np.zeros(5), np.array([0.5, 1.5, 2.9, 3.1, 100.0]))
    np.testing.assert_allclose(static, [17.18e6, 13.521e6, 13.521e6, 20.268e6, 20.268e6])


@pytest.mark.parametrize("lengths", [None, np.full(7, 0.3)])
def test_the_layers_shares_sum_to_one_and_blend_across_each_interface(lengths):
    """Three laws of static stress 1, 2 and 3 Pa under interfaces at 1 and 2 m: the stress is the share-weighted
    sum, so equal stresses give 1 everywhere (the shares sum to 1), and across an interface the blend runs from
    one law to the next over the points' length, centred on it (without lengths, the law below from just under
    the interface)."""
    laws = tuple(ResistanceLaw(c0, 0.0) for c0 in (1.0, 2.0, 3.0))
    depth = np.array([-0.5, 0.5, 0.85, 1.0, 1.15, 1.7, 5.0])
    same = LayeredTarget((1.0, 2.0), (laws[0],) * 3).normal_stress(np.zeros(7), depth, lengths)
    blended = LayeredTarget((1.0, 2.0), laws).normal_stress(np.zeros(7), depth, lengths)
    np.testing.assert_array_equal(same, [1.0] * 7)
    # smooth: from law 1 at 0.15 m (half a length) above the interface to law 2 as far below; sharp: law 2 below it
    expected = [1.0, 1.0, 1.0, 1.5, 2.0, 2.0, 3.0] if lengths is not None else [1.0, 1.0, 1.0, 1.0, 2.0, 2.0, 3.0]
    np.testing.assert_allclose(blended, expected, rtol=1e-15)


def _friction_by_points(loads, position, velocity, rotation, omega):
    """The friction load point by point, straight from its definition (reference for the fast sums)."""
    sigma, vn = loads.stress(position, velocity, rotation, omega)
    q = loads.quadrature
    v_body = rotation.T @ velocity
    force, moment = np.zeros(3), np.zeros(3)
    for i in np.flatnonzero(sigma):
        u = v_body + np.cross(omega, q.points[i])
        slip = u - vn[i] * q.normals[i]
        t = slip / np.linalg.norm(slip)
        f = -loads.friction.stress(sigma[i]) * q.weights[i] * t
        force += f
        moment += np.cross(q.points[i], f)
    return rotation @ force, moment


@pytest.mark.parametrize("cap", [None, 5e6])
def test_fast_friction_sums_equal_the_pointwise_definition(cap):
    profile = PROFILES["paper CRH 5"]
    mesh = meshed(ProjectileGeometry(profile), 0.03, 2)
    quadrature = surface_quadrature(mesh, mass_properties(mesh, {BODY: 1.0}).centre, profile, "exact")
    with_friction = DAFLLoads(quadrature, SOIL, friction=Friction(0.2, cap))
    without = DAFLLoads(quadrature, SOIL)
    rng = np.random.default_rng(7)
    for _ in range(5):
        rotation, _ = np.linalg.qr(rng.normal(size=(3, 3)))
        rotation *= np.sign(np.linalg.det(rotation))
        args = (
            np.array([0.0, 0.0, rng.uniform(-0.8, 0.2)]),
            rng.normal(size=3) * 300,
            rotation,
            rng.normal(size=3) * 40,
        )
        force, moment = with_friction(*args)
        base_force, base_moment = without(*args)
        ref_force, ref_moment = _friction_by_points(with_friction, *args)
        scale = np.abs(ref_force).max() + 1.0
        np.testing.assert_allclose(force - base_force, ref_force, atol=1e-9 * scale)
        np.testing.assert_allclose(moment - base_moment, ref_moment, atol=1e-9 * scale)


def test_the_free_surface_reduction_near_a_rear_face():
    """``f0 + (1 - f0) S(d / D)`` at the distance ``d`` from the nearest face it applies at: both faces of a 0.6 m
    slab, or its rear face alone."""
    from fem_loads.factors import smooth_step_scalars

    depth, fraction, rear = 0.2, 0.3, 0.6
    z = np.array([0.0, 0.05, 0.3, 0.55, 0.6])
    both = FreeSurface(depth, fraction, rear_face=rear).factor(z)
    closest = np.minimum(z, rear - z)
    np.testing.assert_allclose(both, fraction + (1 - fraction) * smooth_step_scalars(closest / depth), rtol=1e-15)
    assert both[0] == both[-1] == fraction and both[2] == 1.0
    np.testing.assert_allclose(both[1], both[3], rtol=1e-12)  # the same distance from either face
    rear_only = FreeSurface(depth, fraction, front=False, rear_face=rear).factor(z)
    assert rear_only[0] == rear_only[1] == 1.0 and rear_only[-1] == fraction
    assert np.array_equal(
        FreeSurface(depth, fraction).factor(z), FreeSurface(depth, fraction, rear_face=np.inf).factor(z)
    )
