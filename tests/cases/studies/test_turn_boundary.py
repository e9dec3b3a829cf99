"""The load-only turn boundary (``penetrate paper``'s prediction of the convergent velocity from the loads alone):
the same speeds from the compiled load as from the numpy one, and the paper's trend with the centre of mass."""

import math

import numpy as np
import pytest

from cases import load_scene, prepare_projectile, scene_path
from cases.run.compiled import compiled_load_function
from cases.studies.reduced.turn_boundary import DEEP, pitch_moment, turn_boundary

COARSE = {"numerics.mesh_size": 0.04}
ANGLES = (4, 8, 12)


def _loads(ratio: float):
    scene = load_scene(scene_path("paper_p3"), {**COARSE, "projectile.centre_of_mass_ratio": ratio})
    prepared = prepare_projectile(scene)
    return scene.loads(prepared.quadrature), prepared.mass.mass


def test_the_compiled_load_gives_the_numpy_load_s_boundary():
    """The study computes the boundary on the compiled load; every crossing and the fold agree with the numpy
    load's to 1e-9 (they differ by the round-off of their sums, and the crossings are found to 0.01 m/s)."""
    loads, mass = _loads(0.5636)
    numpy_boundary = turn_boundary(loads, mass, attack_angles=ANGLES)
    compiled_boundary = turn_boundary(compiled_load_function(loads), mass, attack_angles=ANGLES)
    for field in ("non_rotating", "steady_turn"):
        compiled_speeds = np.array(getattr(compiled_boundary, field), float)
        np.testing.assert_allclose(compiled_speeds, np.array(getattr(numpy_boundary, field), float), rtol=1e-9)
    assert compiled_boundary.fold_speed == pytest.approx(numpy_boundary.fold_speed, rel=1e-9)


def test_the_crossing_is_where_the_pitch_moment_changes_sign():
    loads, mass = _loads(0.5636)
    boundary = turn_boundary(loads, mass, attack_angles=(8,))
    speed = boundary.steady_turn[0]
    assert speed is not None
    below = pitch_moment(loads, mass, speed - 0.5, math.radians(8.0), True)
    above = pitch_moment(loads, mass, speed + 0.5, math.radians(8.0), True)
    assert below * above < 0.0
    assert DEEP[2] < -100.0  # every point inside: the boundary is that of an embedded body


def test_the_fold_speed_falls_as_the_centre_of_mass_moves_back():
    """The paper's trend, which its critical and convergent velocities share: the further back the centre of mass
    (a larger Lc/L, its distance behind the tip over the length), the lower the speed down to which a steady turn
    can hold."""
    folds = []
    for ratio in (0.5042, 0.5636, 0.6230):
        loads, mass = _loads(ratio)
        folds.append(turn_boundary(compiled_load_function(loads), mass, attack_angles=ANGLES).fold_speed)
    assert folds[0] > folds[1] > folds[2] > 0.0
