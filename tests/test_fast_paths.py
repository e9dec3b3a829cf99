"""The speed-ups change no result: the DAFL hot path and the prepared-data disk cache."""

from __future__ import annotations

import numpy as np
import pytest

from cases import load_scene, run_scene, scene_path
from cases.runner import _prepare, _prepared_path, prepare_projectile, preparation_key, scene_loads
from dynamics.quaternion import normalize, rotation_matrix

COARSE = ["numerics.mesh_size=0.04"]


@pytest.fixture(scope="module")
def loads():
    scene = load_scene(scene_path("paper_p3"), COARSE)
    return scene_loads(scene, prepare_projectile(scene))


def _general(loads, position, velocity, rotation, spin):
    """The definition, point by point: sigma from ``stress`` (heights always computed), then the sums."""
    sigma, _ = loads.stress(position, velocity, rotation, spin)
    load = -(sigma * loads._weights) @ loads._normal_arm
    return rotation @ load[:3], load[3:]


@pytest.mark.parametrize("depth", [-5.0, -0.4, 0.0, 0.3, 2.0], ids=["embedded", "entering", "at-surface",
                                                                    "tip-in", "outside"])
def test_hot_path_equals_the_definition(loads, depth):
    rng = np.random.default_rng(7)
    assert loads._plain
    for _ in range(20):
        rotation = rotation_matrix(normalize(rng.normal(size=4)))
        velocity = rng.normal(size=3) * 300.0
        spin = rng.normal(size=3) * 20.0
        position = np.array([0.0, 0.0, depth]) + rng.normal(size=3) * 0.1
        force, moment = loads(position, velocity, rotation, spin)
        force_ref, moment_ref = _general(loads, position, velocity, rotation, spin)
        scale = max(np.abs(force_ref).max(), 1.0)
        np.testing.assert_allclose(force, force_ref, rtol=0, atol=1e-12 * scale)
        np.testing.assert_allclose(moment, moment_ref, rtol=0, atol=1e-12 * max(np.abs(moment_ref).max(), 1.0))


def test_bounding_sphere_shortcuts_are_exact(loads):
    rng = np.random.default_rng(3)
    for _ in range(50):
        rotation = rotation_matrix(normalize(rng.normal(size=4)))
        position = np.array([0.0, 0.0, rng.uniform(-2.0, 2.0)])
        heights = loads.heights(position, rotation)
        if loads.fully_embedded(position):
            assert heights.max() < 0.0
        if loads.fully_outside(position):
            assert heights.min() >= 0.0


def test_prepared_projectile_comes_back_bit_identical_from_the_disk_cache():
    scene = load_scene(scene_path("forrestal_luk_test5"), COARSE)
    first = prepare_projectile(scene)
    path = _prepared_path(*preparation_key(scene))
    assert path.exists()
    _prepare.cache_clear()  # forget the in-memory copy: the next one is read from disk
    again = prepare_projectile(scene)
    assert again is not first
    for name in ("points", "normals", "weights", "moment_arms"):
        np.testing.assert_array_equal(getattr(again.quadrature, name), getattr(first.quadrature, name))
    np.testing.assert_array_equal(again.mass.inertia, first.mass.inertia)
    np.testing.assert_array_equal(again.mass.centre, first.mass.centre)
    assert again.mass.mass == first.mass.mass and again.n_tetra == first.n_tetra
    # a corrupt entry is recomputed, not trusted
    path.write_bytes(b"not an npz file")
    _prepare.cache_clear()
    recomputed = prepare_projectile(scene)
    np.testing.assert_array_equal(recomputed.quadrature.weights, first.quadrature.weights)
    assert path.stat().st_size > 1000


def test_runs_from_the_cache_and_from_scratch_agree_bitwise():
    scene = load_scene(scene_path("forrestal_luk_test2"), COARSE)
    _prepared_path(*preparation_key(scene)).unlink(missing_ok=True)
    _prepare.cache_clear()
    cold = run_scene(scene).trajectory  # mass properties and quadrature assembled by scikit-fem
    _prepare.cache_clear()
    warm = run_scene(scene).trajectory  # read back from the disk cache
    np.testing.assert_array_equal(cold.position, warm.position)
    np.testing.assert_array_equal(cold.attitude, warm.attitude)
