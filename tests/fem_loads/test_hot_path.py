"""The DAFL resultant (its mirror images' folded sums) equals the definition, point by point, on random states."""

from __future__ import annotations

import numpy as np
import pytest

from cases import load_scene, prepare_projectile, scene_path
from dynamics.quaternion import normalize, rotation_matrix

COARSE = {"numerics.mesh_size": 0.04}


@pytest.fixture(scope="module")
def loads():
    scene = load_scene(scene_path("paper_p3"), COARSE)
    return scene.loads(prepare_projectile(scene).quadrature)


def _general(loads, position, velocity, rotation, spin):
    """The definition, point by point: sigma from ``stress`` (heights always computed), then the sums."""
    sigma, _ = loads.stress(position, velocity, rotation, spin)
    arrays = loads.point_arrays()
    load = -arrays["normal_arm"] @ (sigma * arrays["weights"])
    return rotation @ load[:3], load[3:]


@pytest.mark.parametrize(
    "depth", [-5.0, -0.4, 0.0, 0.3, 2.0], ids=["embedded", "entering", "at-surface", "tip-in", "outside"]
)
def test_hot_path_equals_the_definition(loads, depth):
    rng = np.random.default_rng(7)
    assert loads.quadrature.mirror_images is not None  # the folded sums are the ones under test
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
