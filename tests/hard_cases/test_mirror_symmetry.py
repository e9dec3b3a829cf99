"""Exact mirror symmetry: mesh, mass properties, quadrature, loads and start attitude.

A straight normal impact, and the mirror image of any run, must stay exactly so (bitwise): these
tests check each piece the long-run tests in test_hard_cases.py rely on, against independent truth
(the plain sum over every point, the column-built start attitude).
"""

from __future__ import annotations

import functools
import math

import numpy as np
import pytest
from support import MIRROR_Y, meshed, mirrored_states

from cases.run.runner import initial_attitude
from dynamics.quaternion import rotation_matrix
from fem_loads import (
    DAFLLoads,
    SurfaceQuadrature,
    find_mirror_images,
    mass_properties,
    resistance_law,
    surface_quadrature,
)
from fem_loads.images import MirrorImages
from fem_loads.mass import mirror_symmetric_axes
from fem_loads.quadrature import MIRROR_SIGNS
from mesh import BODY, OgiveNose, Profile, ProjectileGeometry

PROFILE = Profile(0.155, 0.93, OgiveNose(5.0))
SOIL = resistance_law("soil")
SIGNS = [np.array([1.0, sy, sz]) for sy, sz in MIRROR_SIGNS]


@functools.cache
def _mesh(order: int):
    return meshed(ProjectileGeometry(PROFILE), 0.04, order)


@functools.cache
def _quadrature(order: int, model: str) -> SurfaceQuadrature:
    mesh = _mesh(order)
    return surface_quadrature(mesh, mass_properties(mesh, {BODY: 1.0}).centre, PROFILE, model)


@pytest.mark.parametrize("order", [1, 2])
def test_mesh_mass_properties_have_exact_zeros(order):
    """The mesh is its own mirror image in y = 0 and z = 0; odd moments are exact zeros, even ones untouched."""
    mesh = _mesh(order)
    assert mirror_symmetric_axes(mesh) == (1, 2)
    mass = mass_properties(mesh, {BODY: 7850.0})
    assert mass.centre[1] == mass.centre[2] == 0.0
    assert not (mass.inertia - np.diag(np.diag(mass.inertia))).any()
    assert mass.inertia[1, 1] == pytest.approx(mass.inertia[2, 2], rel=1e-3)


def test_an_asymmetric_mesh_keeps_its_products_of_inertia():
    """A node and its image in z = 0 moved in y: the y mirror is not claimed and its odd moments are computed."""
    mesh = _mesh(1)
    points = mesh.points.copy()
    inner = int(np.argmax((np.abs(points[:, 1]) > 0.02) & (np.abs(points[:, 2]) > 0.02) & (points[:, 0] < -0.5)))
    image = int(np.flatnonzero((points == points[inner] * np.array([1.0, 1.0, -1.0])).all(axis=1))[0])
    points[[inner, image], 1] += 1e-3
    moved = type(mesh)(points, mesh.tetra, mesh.tetra_region, mesh.outer, mesh.order)
    assert mirror_symmetric_axes(moved) == (2,)
    mass = mass_properties(moved, {BODY: 7850.0})
    assert mass.centre[1] != 0.0 and mass.inertia[0, 1] != 0.0
    assert mass.centre[2] == 0.0 and mass.inertia[0, 2] == 0.0


@pytest.mark.parametrize(("order", "model"), [(1, "mesh"), (1, "exact"), (2, "mesh"), (2, "exact")])
def test_quadrature_is_mirror_symmetric_bitwise(order, model):
    q = _quadrature(order, model)
    images = q.mirror_images
    assert images is not None and images.shape == (4, len(q) // 4)
    assert sorted(images.ravel().tolist()) == list(range(len(q)))
    quarter = images[0]
    assert (q.points[quarter, 1] > 0).all() and (q.points[quarter, 2] > 0).all()
    for partner, signs in zip(images, SIGNS):
        assert np.array_equal(q.points[partner], q.points[quarter] * signs)
        assert np.array_equal(q.normals[partner], q.normals[quarter] * signs)
        assert np.array_equal(q.weights[partner], q.weights[quarter])


def test_symmetrising_moves_points_by_round_off_only():
    """The rewritten images were already the images to round-off (each point stays in its facet)."""
    mesh = _mesh(2)
    centre = mass_properties(mesh, {BODY: 1.0}).centre
    raw = surface_quadrature(mesh, centre, PROFILE, "exact")
    images = find_mirror_images(raw.points)
    # recompute the unsymmetrised quadrature through the module's steps, without the rewrite
    from skfem import ElementTetP0, FacetBasis

    from fem_loads.quadrature import _facet_indices, _to_exact_surface, to_skfem

    m = to_skfem(mesh)
    corners = np.searchsorted(np.unique(mesh.tetra[:, :4]), mesh.outer[:, :3])
    fb = FacetBasis(m, ElementTetP0(), facets=_facet_indices(m, corners), intorder=2)
    points = np.asarray(fb.global_coordinates()).reshape(3, -1).T
    normals = np.asarray(fb.normals).reshape(3, -1).T
    normals = normals / np.linalg.norm(normals, axis=1)[:, None]
    points, normals, weights = _to_exact_surface(points, normals, fb.dx.reshape(-1), PROFILE)
    assert np.array_equal(images, raw.mirror_images)
    assert np.abs(raw.points - (points - centre)).max() < 1e-14
    assert np.abs(raw.normals - normals).max() < 1e-12
    assert np.abs(raw.weights - weights).max() < 1e-12 * weights.max()


def test_asymmetric_points_have_no_mirror_images():
    q = _quadrature(1, "exact")
    moved = q.points.copy()
    moved[q.mirror_images[1][5], 0] += 1e-6  # one image no longer matches
    assert find_mirror_images(moved) is None
    on_plane = q.points.copy()
    on_plane[0, 1] = 0.0  # a point on y = 0 belongs to no quarter
    assert find_mirror_images(on_plane) is None
    assert find_mirror_images(np.random.default_rng(0).normal(size=(400, 3))) is None


def _random_state(rng: np.random.Generator):
    q = rng.normal(size=4)
    return (
        np.array([0.0, 0.0, rng.uniform(-1.5, -0.2)]),
        rng.normal(size=3) * 300.0,
        rotation_matrix(q / np.linalg.norm(q)),
        rng.normal(size=3) * 20.0,
    )


def _plain_sum(loads: DAFLLoads, position, velocity, rotation, spin):
    """The definition over every point in the quadrature's order, without the images."""
    sigma, _ = loads.stress(position, velocity, rotation, spin)
    load = -(sigma * loads.quadrature.weights) @ loads._normal_arm
    return np.concatenate([rotation @ load[:3], load[3:]])


@pytest.mark.parametrize("reproducible", [True, False], ids=["one-product", "per-image"])
def test_image_sums_equal_the_plain_sum(reproducible):
    """Random (asymmetric) states, entering and embedded: the same load as the plain sum to round-off."""
    loads = DAFLLoads(_quadrature(2, "exact"), SOIL)
    assert loads._images.reproducible  # OpenBLAS: one product gives bitwise-equal images
    loads._images.reproducible = reproducible
    rng = np.random.default_rng(11)
    for _ in range(30):
        state = _random_state(rng)
        load = np.concatenate(loads(*state))
        reference = _plain_sum(loads, *state)
        np.testing.assert_allclose(load, reference, rtol=0, atol=1e-12 * np.abs(reference).max())


@pytest.mark.parametrize("reproducible", [True, False], ids=["one-product", "per-image"])
def test_symmetric_states_give_exactly_symmetric_loads(reproducible):
    """A state symmetric about the body plane z = 0 (pitching in the xy plane) gives F_z = M_x = M_y = 0 exactly;
    axial motion spinning about the axis (symmetric under the half turn about it) gives F_y = F_z = M_y = M_z = 0.
    """
    loads = DAFLLoads(_quadrature(1, "exact"), SOIL)
    loads._images.reproducible = reproducible
    nose_down = rotation_matrix(np.array([math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0]))
    rng = np.random.default_rng(5)
    for depth in (-0.3, -3.0):  # entering (heights computed), embedded
        position = np.array([0.0, 0.0, depth])
        for _ in range(10):
            # body-frame velocity (u, v, 0) and angular velocity (0, 0, r): symmetric about body z = 0
            body_velocity = np.array([rng.uniform(100, 900), rng.normal() * 50, 0.0])
            force, moment = loads(position, nose_down @ body_velocity, nose_down, np.array([0.0, 0.0, rng.normal()]))
            body_force = nose_down.T @ force
            assert body_force[2] == 0.0 and moment[0] == 0.0 and moment[1] == 0.0
            assert body_force[1] != 0.0 and moment[2] != 0.0
        # axial motion spinning about the axis: symmetric under the half turn about the axis (both images)
        force, moment = loads(position, nose_down @ np.array([500.0, 0.0, 0.0]), nose_down, np.array([30.0, 0, 0]))
        assert force[0] == force[1] == 0.0 and moment[1] == moment[2] == 0.0 and force[2] > 0


def test_mirrored_states_give_exactly_mirrored_loads():
    """A state and its image in the world plane Y = 0: the loads are images of each other, bitwise."""
    loads = DAFLLoads(_quadrature(2, "exact"), SOIL)
    mirror = np.array(MIRROR_Y)
    for state, image in mirrored_states(np.random.default_rng(2)):
        assert np.array_equal(image[2], mirror @ state[2] @ mirror)  # the image quaternion's rotation, exactly
        force, moment = loads(*state)
        image_force, image_moment = loads(*image)
        assert np.array_equal(image_force, mirror @ force)
        assert np.array_equal(image_moment, -(mirror @ moment))


def test_images_scatter_inverts_the_images_rows():
    q = _quadrature(1, "exact")
    images = MirrorImages(
        q.mirror_images,
        q.mirror_signs,
        np.ascontiguousarray(np.hstack([q.normals, q.moment_arms]).T),
        np.ascontiguousarray(q.points.T),
    )
    values = np.random.default_rng(0).normal(size=len(q))
    assert np.array_equal(images.scatter(values[images.images]), values)  # per point -> rows (k, m) -> per point


def _attitude_from_columns(oblique: float, attack: float, yaw: float) -> np.ndarray:
    """The start attitude as its definition states it: the axis, then the side axis in the plane of the axis and Y."""
    phi, psi = math.radians(oblique + attack), math.radians(yaw)
    axis = math.cos(psi) * np.array([math.sin(phi), 0.0, -math.cos(phi)]) + math.sin(psi) * np.array([0.0, 1.0, 0.0])
    side = np.array([0.0, 1.0, 0.0]) - axis[1] * axis
    side /= np.linalg.norm(side)
    return np.column_stack([axis, side, np.cross(axis, side)])


def test_start_attitude_matches_its_definition_and_is_exact_nose_down():
    rng = np.random.default_rng(4)
    for oblique, attack, yaw in zip(rng.uniform(0, 85, 300), rng.uniform(-20, 20, 300), rng.uniform(-45, 45, 300)):
        q = initial_attitude(oblique, attack, yaw)
        assert abs(float(q @ q) - 1.0) < 1e-15
        np.testing.assert_allclose(rotation_matrix(q), _attitude_from_columns(oblique, attack, yaw), atol=1e-15)
    q = initial_attitude(0.0, 0.0, 0.0)
    assert q[0] == q[2] and q[1] == q[3] == 0.0
    rotation = rotation_matrix(q)
    # body x exactly down, body y exactly Y: a straight impact has an exactly axial body velocity
    assert rotation[0, 0] == rotation[1, 0] == rotation[2, 2] == rotation[2, 1] == 0.0 and rotation[2, 0] < 0
    assert np.array_equal(np.array([0.0, 0.0, -500.0]) @ rotation * np.array([0, 1, 1]), np.zeros(3))


def test_a_quadrature_without_mirror_quarters_uses_the_plain_sums():
    """The same points without their quarters (as for an asymmetric surface): plain sums, the same load."""
    q = _quadrature(2, "exact")
    symmetric = DAFLLoads(q, SOIL)
    plain = DAFLLoads(SurfaceQuadrature(q.points, q.normals, q.weights), SOIL)
    assert symmetric._images is not None and plain._images is None
    rng = np.random.default_rng(8)
    for _ in range(20):
        state = _random_state(rng)
        a, b = np.concatenate(symmetric(*state)), np.concatenate(plain(*state))
        np.testing.assert_allclose(a, b, rtol=0, atol=1e-12 * np.abs(b).max())


# a quadrature with one mirror plane: the two-plane one sheared along x by the other coordinate (x += 0.05 y
# keeps the plane z = 0 and breaks y = 0; x += 0.05 z the reverse), its normals recomputed as the shear maps them
def _one_plane(axis: int) -> SurfaceQuadrature:
    q = _quadrature(2, "exact")
    other = 3 - axis
    shear = np.eye(3)
    shear[0, other] = 0.05
    normals = q.normals @ np.linalg.inv(shear)
    return SurfaceQuadrature(
        q.points @ shear.T,
        normals / np.linalg.norm(normals, axis=1)[:, None],
        q.weights,
        find_mirror_images(q.points @ shear.T),
    )


@pytest.mark.parametrize("axis", [1, 2], ids=["plane y=0", "plane z=0"])
def test_one_mirror_plane_is_found_and_its_halves_are_exact_images(axis):
    q = _one_plane(axis)
    assert q.mirror_images is not None and q.mirror_images.shape == (2, len(q) // 2)
    assert q.mirror_planes == (axis,)
    half, partner = q.mirror_images
    signs = np.array([1.0, 1.0, 1.0])
    signs[axis] = -1.0
    assert (q.points[half, axis] > 0).all()
    assert np.array_equal(q.points[partner], q.points[half] * signs)
    assert np.array_equal(q.normals[partner], q.normals[half] * signs)


@pytest.mark.parametrize("kernel", ["numpy", "numpy per image", "compiled"])
@pytest.mark.parametrize("axis", [1, 2], ids=["plane y=0", "plane z=0"])
def test_one_mirror_plane_keeps_a_state_in_it_exactly(axis, kernel):
    """A state symmetric about the body's one mirror plane (moving and turning in it) gives exactly no force
    across the plane and no moment out of it, entering and embedded, and the plain sums' load to round-off."""
    loads = DAFLLoads(_one_plane(axis), SOIL, contact_incidence=0.005, entry_smoothing=4.0)
    if kernel == "numpy per image":
        loads._images.reproducible = False
    if kernel == "compiled":
        from cases.run.compiled import compiled_modules

        layout = compiled_modules()[1]
        data = layout.kernel_data(loads)

        def load(*state):
            out = np.empty(6)
            layout.dafl_kernel(data, *state, out)
            return out[:3], out[3:]
    else:
        load = loads
    plain = DAFLLoads(
        SurfaceQuadrature(loads.quadrature.points, loads.quadrature.normals, loads.quadrature.weights),
        SOIL,
        contact_incidence=0.005,
        entry_smoothing=4.0,
    )
    nose_down = rotation_matrix(np.array([math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0]))
    other = 3 - axis
    rng = np.random.default_rng(12)
    for depth in (-0.3, -3.0):
        position = np.array([0.0, 0.0, depth])
        for _ in range(10):
            body_velocity = np.zeros(3)
            body_velocity[0], body_velocity[other] = rng.uniform(100, 900), rng.normal() * 50
            spin = np.zeros(3)
            spin[axis] = rng.normal()  # turning about the plane's normal: the motion stays in the plane
            state = (position, nose_down @ body_velocity, nose_down, spin)
            force, moment = load(*state)
            body_force = nose_down.T @ force
            assert body_force[axis] == 0.0 and moment[0] == 0.0 and moment[other] == 0.0
            assert body_force[other] != 0.0 and moment[axis] != 0.0
            reference = np.concatenate(plain(*state))
            np.testing.assert_allclose(
                np.concatenate([force, moment]), reference, rtol=0, atol=1e-12 * np.abs(reference).max()
            )


@pytest.mark.parametrize("axis", [1, 2], ids=["plane y=0", "plane z=0"])
def test_the_plane_of_images_that_match_to_round_off_only_is_theirs(axis):
    """Images found before they are rewritten (as surface_quadrature finds them) differ from exact ones in their
    last bits: their plane is still the one across which they lie."""
    q = _one_plane(axis)
    noisy = q.points * (1.0 + 1e-13 * np.random.default_rng(3).normal(size=q.points.shape))
    images = find_mirror_images(noisy)
    assert images is not None and SurfaceQuadrature(noisy, q.normals, q.weights, images).mirror_planes == (axis,)
