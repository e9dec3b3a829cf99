"""The target's front face (fem_loads.target.FrontFace): a point's height above it is one function of the face
(face_frame_scalars), and every kernel calls it.  A face turned and moved with the whole scene turns and moves
the load with it; the level face is exactly the half-space Z < 0."""

from __future__ import annotations

import numpy as np
import pytest

from cases import load_scene, prepare_projectile, scene_path
from cases.run.compiled import _import_compiled
from dynamics.quaternion import normalize, rotation_matrix
from fem_loads import DAFLLoads, SurfaceQuadrature, resistance_law
from fem_loads.target import LEVEL, FreeSurface, Friction, FrontFace, face_frame_scalars

_, compiled = _import_compiled()  # numba's cache in the folder named for the compiled code

SOIL = resistance_law("soil")
SMOOTH = {"contact_incidence": 0.005, "entry_smoothing": 4.0}
EFFECTS = {
    "plain": SMOOTH,
    "friction and surface": {**SMOOTH, "friction": Friction(0.1, 2e6), "free_surface": FreeSurface(0.3, 0.2)},
    "sharp": {},
}


@pytest.fixture(scope="module")
def quadrature() -> SurfaceQuadrature:
    return prepare_projectile(load_scene(scene_path("paper_p3"), {"numerics.mesh_size": 0.04})).quadrature


def _numpy(loads: DAFLLoads, state) -> np.ndarray:
    return np.concatenate(loads(*state))


def _compiled(loads: DAFLLoads, state) -> np.ndarray:
    out = np.empty(6)
    compiled.dafl_kernel(compiled.kernel_data(loads), *state, out)
    return out


def test_the_level_face_is_exactly_the_centre_s_height_and_the_last_row_of_the_rotation():
    rng = np.random.default_rng(3)
    for _ in range(200):
        position, rotation = rng.normal(size=3), rotation_matrix(normalize(rng.normal(size=4)))
        height, *up = face_frame_scalars(position, rotation, LEVEL.normal, LEVEL.offset)
        assert height == position[2] and np.array_equal(up, rotation[2])


@pytest.mark.parametrize("kernel", [_numpy, _compiled], ids=["numpy", "compiled"])
@pytest.mark.parametrize("effects", list(EFFECTS))
def test_turning_and_moving_the_face_with_the_scene_turns_and_moves_the_load(quadrature, kernel, effects):
    """Face n = Q e_z through d n, state (Q X + d n, Q V, Q R, omega): the force turns by Q, the body-frame moment
    is unchanged (to round-off; the sharp switches only where no point sits on them)."""
    rng = np.random.default_rng(11)
    level = DAFLLoads(quadrature, SOIL, **EFFECTS[effects])
    for _ in range(8):
        turn = rotation_matrix(normalize(rng.normal(size=4)))
        offset = rng.normal() * 3.0
        face = FrontFace(tuple(turn[:, 2]), offset)
        tilted = DAFLLoads(quadrature, SOIL, front_face=face, **EFFECTS[effects])
        rotation = rotation_matrix(normalize(rng.normal(size=4)))
        position = np.array([0.1, -0.2, rng.uniform(-0.6, 0.2)])
        velocity, spin = rng.normal(size=3) * 300.0, rng.normal(size=3) * 20.0
        reference = kernel(level, (position, velocity, rotation, spin))
        moved = (turn @ position + offset * turn[:, 2], turn @ velocity, turn @ rotation, spin)
        got = kernel(tilted, moved)
        scale = np.abs(reference).max()
        assert scale > 0.0
        np.testing.assert_allclose(got[:3], turn @ reference[:3], rtol=0, atol=1e-9 * scale)
        np.testing.assert_allclose(got[3:], reference[3:], rtol=0, atol=1e-9 * scale)


@pytest.mark.parametrize("face", [FrontFace((0.0, 0.6, 0.8), -0.2), FrontFace((1.0, 0.0, 0.0), 0.3)])
def test_the_compiled_exit_height_is_the_numpy_one_for_any_face(quadrature, face):
    loads = DAFLLoads(quadrature, SOIL, front_face=face, **SMOOTH)
    data = compiled.kernel_data(loads)
    rng = np.random.default_rng(4)
    straddling = 0
    for _ in range(40):
        position = rng.normal(size=3) * 0.5
        rotation = rotation_matrix(normalize(rng.normal(size=4)))
        got, want = compiled.lowest_height_kernel(data, position, rotation), loads.lowest_height(position, rotation)
        if float(np.dot(face.normal, position)) - face.offset + loads.max_radius < 0.0:
            assert want <= got < 0.0  # wholly inside: the bounding sphere's top, a negative upper bound
        else:
            straddling += 1
            assert got == pytest.approx(want, abs=1e-12)
    assert straddling > 10


@pytest.mark.parametrize(
    "normal, offset, message",
    [
        ((0.0, 0.0, 2.0), 0.0, "front face normal = (0.0, 0.0, 2.0): must be a unit vector"),
        ((0.0, 1.0), 0.0, "must be a unit vector of 3 finite numbers"),
        ((0.0, float("nan"), 1.0), 0.0, "must be a unit vector"),
        ((0.0, 0.0, 1.0), float("inf"), "front face offset = inf: must be a finite number"),
    ],
)
def test_a_bad_face_is_refused_in_one_line(normal, offset, message):
    with pytest.raises(ValueError, match=message.replace("(", r"\(").replace(")", r"\)")) as error:
        FrontFace(normal, offset)
    assert "\n" not in str(error.value)
