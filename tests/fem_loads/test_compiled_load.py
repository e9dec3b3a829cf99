"""The compiled DAFL kernel (fem_loads/kernels/mesh_loop.py) computes the numpy load: on random states, in every
switch mode, with and without mirror quarters; symmetric states stay exactly symmetric."""

from __future__ import annotations

import math

import numpy as np
import pytest
from support import MIRROR_Y, mirrored_states

from cases import load_scene, prepare_projectile, scene_path
from cases.run.compiled import _import_compiled
from dynamics.quaternion import normalize, rotation_matrix
from fem_loads import DAFLLoads, ResistanceLaw, SurfaceQuadrature, resistance_law
from fem_loads.kernels.records import compilable
from fem_loads.target import GAP, FreeSurface, Friction, LayeredTarget

_, compiled = _import_compiled()  # numba's cache in the folder named for the compiled code

COARSE = {"numerics.mesh_size": 0.04}
SOIL = resistance_law("soil")
# the scenes' default switches, and the sharp ones of the paper's law
SMOOTH = {"contact_incidence": 0.005, "entry_smoothing": 4.0}
MODES = {
    "smooth": SMOOTH,
    "sharp": {},
    "sharp-contact": {"entry_smoothing": 4.0},
    "sharp-entry": {"contact_incidence": 0.005, "contact_width": 1.0},
}


@pytest.fixture(scope="module")
def quadrature() -> SurfaceQuadrature:
    scene = load_scene(scene_path("paper_p3"), COARSE)
    return prepare_projectile(scene).quadrature


def _kernel_load(loads: DAFLLoads, state) -> np.ndarray:
    out = np.empty(6)
    compiled.dafl_kernel(compiled.kernel_data(loads), *state, out)
    return out


def _random_state(rng: np.random.Generator, depth: float):
    rotation = rotation_matrix(normalize(rng.normal(size=4)))
    return (
        np.array([0.0, 0.0, depth]) + rng.normal(size=3) * 0.1,
        rng.normal(size=3) * 300.0,
        rotation,
        rng.normal(size=3) * 20.0,
    )


@pytest.mark.parametrize("mode", list(MODES))
@pytest.mark.parametrize("depth", [-5.0, -0.4, 0.3, 2.0], ids=["embedded", "entering", "tip-in", "outside"])
def test_kernel_equals_the_numpy_load(quadrature, mode, depth):
    loads = DAFLLoads(quadrature, SOIL, **MODES[mode])
    rng = np.random.default_rng(17)
    for _ in range(20):
        state = _random_state(rng, depth)
        reference = np.concatenate(loads(*state))
        scale = max(np.abs(reference).max(), 1.0)
        np.testing.assert_allclose(_kernel_load(loads, state), reference, rtol=0, atol=1e-12 * scale)
    outside = (np.array([0.0, 0.0, 5.0]), *_random_state(rng, 0.0)[1:])
    assert np.array_equal(_kernel_load(loads, outside), np.zeros(6))


def test_kernel_without_mirror_images(quadrature):
    """The same points as one image (an asymmetric surface's layout): the same load."""
    plain = SurfaceQuadrature(quadrature.points, quadrature.normals, quadrature.weights)
    assert plain.mirror_images is None
    loads, reference_loads = DAFLLoads(plain, SOIL, **SMOOTH), DAFLLoads(quadrature, SOIL, **SMOOTH)
    assert compiled.kernel_data(loads)[compiled.KERNEL_ARRAYS.index("image_signs")].shape == (1, 6)
    rng = np.random.default_rng(8)
    for _ in range(20):
        state = _random_state(rng, -0.5)
        reference = np.concatenate(reference_loads(*state))
        np.testing.assert_allclose(_kernel_load(loads, state), reference, rtol=0, atol=1e-12 * np.abs(reference).max())


@pytest.mark.parametrize("mode", ["smooth", "sharp"])
def test_symmetric_states_give_exactly_symmetric_loads(quadrature, mode):
    """Pitching in the body xy plane: F_z = M_x = M_y = 0 exactly; spinning about the axis: no lateral load."""
    loads = DAFLLoads(quadrature, SOIL, **MODES[mode])
    nose_down = rotation_matrix(np.array([math.sqrt(0.5), 0.0, math.sqrt(0.5), 0.0]))
    rng = np.random.default_rng(5)
    for depth in (-0.3, -3.0):
        position = np.array([0.0, 0.0, depth])
        for _ in range(10):
            body_velocity = np.array([rng.uniform(100, 900), rng.normal() * 50, 0.0])
            load = _kernel_load(
                loads, (position, nose_down @ body_velocity, nose_down, np.array([0.0, 0.0, rng.normal()]))
            )
            body_force = nose_down.T @ load[:3]
            assert body_force[2] == 0.0 and load[3] == 0.0 and load[4] == 0.0
            assert body_force[1] != 0.0 and load[5] != 0.0
        load = _kernel_load(
            loads, (position, nose_down @ np.array([500.0, 0.0, 0.0]), nose_down, np.array([30.0, 0.0, 0.0]))
        )
        assert load[0] == load[1] == 0.0 and load[4] == load[5] == 0.0 and load[2] > 0


def test_mirrored_states_give_exactly_mirrored_loads(quadrature):
    loads = DAFLLoads(quadrature, SOIL, **SMOOTH)
    mirror = np.array(MIRROR_Y)
    for state, image in mirrored_states(np.random.default_rng(2)):
        load, image_load = _kernel_load(loads, state), _kernel_load(loads, image)
        assert np.array_equal(image_load[:3], mirror @ load[:3])
        assert np.array_equal(image_load[3:], -(mirror @ load[3:]))


@pytest.mark.parametrize("mode", ["smooth", "sharp"])
def test_lowest_height_equals_the_numpy_one(quadrature, mode):
    loads = DAFLLoads(quadrature, SOIL, **MODES[mode])
    data = compiled.kernel_data(loads)
    rng = np.random.default_rng(4)
    for _ in range(20):
        position, _, rotation, _ = _random_state(rng, -0.3)
        assert compiled.lowest_height_kernel(data, position, rotation) == pytest.approx(
            loads.lowest_height(position, rotation), abs=1e-14
        )


SLAB = LayeredTarget((0.6,), (SOIL, GAP))
LAYERS = LayeredTarget((0.2, 0.5), (SOIL, resistance_law("softer_soil"), ResistanceLaw(2e6, 1e3, c1=3e4)))
#: every effect and law of the kernel, each alone and some together (with the default smooth switches)
EFFECTS = {
    "coulomb": {"friction": Friction(0.1)},
    "capped": {"friction": Friction(0.3, 4e6)},
    "no-separation": {"separation": False},
    "free-surface": {"free_surface": FreeSurface(0.3, 0.2)},
    "layers": {"law": LAYERS},
    "centred": {"contact": "centred"},
    "polynomial": {"law": ResistanceLaw(3e6, 800.0, c1=2e4)},
    "power": {"law": ResistanceLaw(4e6, 0.0, c=5e3, n=1.6)},
    "depth-gradient": {"law": ResistanceLaw(3e6, 1e3, k=2e6)},
    "table": {"law": ResistanceLaw(3e6, 1e3, strength_table=((0.0, 0.0), (0.3, 5e6), (1.0, 6e6)))},
    "all": {"law": LAYERS, "friction": Friction(0.2), "free_surface": FreeSurface(0.3), "contact": "centred"},
    # a 0.6 m slab reduced near both faces, and near its rear face alone
    "slab-both-faces": {"law": SLAB, "free_surface": FreeSurface(0.3, 0.2, rear_face=0.6)},
    "slab-rear-face": {"law": SLAB, "free_surface": FreeSurface(0.3, 0.2, front=False, rear_face=0.6)},
}


@pytest.mark.parametrize("effect", list(EFFECTS))
@pytest.mark.parametrize("sharp", [False, True], ids=["smooth", "sharp"])
@pytest.mark.parametrize("depth", [-5.0, -0.4, 0.3], ids=["embedded", "entering", "tip-in"])
def test_kernel_computes_every_effect_as_numpy_does(quadrature, effect, sharp, depth):
    options = {"law": SOIL, **({} if sharp else SMOOTH), **EFFECTS[effect]}
    if sharp and "contact" in options:
        options["contact_incidence"] = 0.005
    loads = DAFLLoads(quadrature, options.pop("law"), **options)
    assert compilable(loads.law)
    rng = np.random.default_rng(23)
    for _ in range(10):
        state = _random_state(rng, depth)
        reference = np.concatenate(loads(*state))
        scale = max(np.abs(reference).max(), 1.0)
        np.testing.assert_allclose(_kernel_load(loads, state), reference, rtol=0, atol=1e-11 * scale)


def test_the_compiled_strength_table_is_np_interp_at_every_depth():
    """A point's table stress in compiled code (without numba's np.interp, which builds arrays for one value) equals
    ``np.interp`` exactly: before the first row, on each row, between rows, and past the last."""
    from numba import njit

    from fem_loads.resistance import table_stress_scalars

    at_a_point = njit(lambda depth, depths, stresses: table_stress_scalars(depth, depths, stresses))
    depths, stresses = np.array([0.0, 0.3, 0.3 + 1e-9, 1.0, 4.0]), np.array([1e6, 5e6, -2e6, 6.5e6, 6.5e6])
    for depth in (-1.0, 0.0, 1e-300, 0.1, 0.3, 0.3 + 5e-10, 0.7, 1.0, 2.5, 4.0, 9.0):
        assert at_a_point(depth, depths, stresses) == np.interp(depth, depths, stresses), depth
