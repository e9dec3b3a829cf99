"""The example laws of cases/laws, named by scenes: each is usable, and the one equal to the built-in soil law
gives test 2's depth to 1e-9 on both kernels, as the polynomial law with c1 = 0 and the depth-dependent
law with k = 0 do."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

import cases
from cases import load_scene, run_scene, scene_path
from fem_loads.resistance import resistance_law
from fem_loads.user_law import user_law

LAWS = Path(cases.__file__).parent / "laws" / "soil_laws.py"
SOIL = resistance_law("soil")
EXAMPLES = {
    "cavity_expansion": ({"c0": 1e7, "c2": 2e3}, lambda v, z: 1e7 + 2e3 * v**2),
    "overburden": (
        {"c0": 1e7, "c2": 2e3, "unit_weight": 1.8e4, "lateral_ratio": 0.5},
        lambda v, z: 1e7 + 0.5 * 1.8e4 * np.maximum(z, 0.0) + 2e3 * v**2,
    ),
    "rate_hardening": (
        {"c0": 1e7, "c2": 2e3, "reference_speed": 100.0, "exponent": 0.5},
        lambda v, z: 1e7 * (1 + np.sqrt(v / 100.0)) + 2e3 * v**2,
    ),
}


@pytest.mark.parametrize("name", list(EXAMPLES))
def test_each_example_law_is_usable_and_is_its_formula(name):
    parameters, formula = EXAMPLES[name]
    law = user_law(f"{LAWS}:{name}", parameters)
    v, z = np.meshgrid([0.0, 10.0, 400.0], [-0.01, 0.5, 12.0], indexing="ij")
    np.testing.assert_allclose(law.normal_stress(v, z), formula(v, z), rtol=1e-14)


EQUAL_TO_SOIL = {
    "user law": {
        "target.law": {
            "function": f"{LAWS}:cavity_expansion",
            "parameters": {"c0": SOIL.c0, "c2": SOIL.c2},
        }
    },
    "polynomial, c1 = 0": {"target.law": {"model": "polynomial", "c0": SOIL.c0, "c1": 0.0, "c2": SOIL.c2}},
    "k = 0": {"target.law": {"A": 1.718, "sigma_0": 10e6, "B": 1.227, "rho_0": 1860.0, "depth_gradient": 0.0}},
}


@pytest.fixture(scope="module")
def soil_depths() -> dict[str, float]:
    return {kernel: _depth({}, kernel) for kernel in ("numpy", "compiled")}


def _depth(overrides: dict, kernel: str) -> float:
    scene = load_scene(scene_path("forrestal_luk_test2"), {**overrides, "numerics.kernel": kernel})
    return abs(float(run_scene(scene).trajectory.position[-1][2]))


@pytest.mark.parametrize("kernel", ["numpy", "compiled"])
@pytest.mark.parametrize("law", list(EQUAL_TO_SOIL))
def test_a_law_equal_to_the_soil_law_gives_test_2_s_depth(soil_depths, law, kernel):
    depth = _depth(EQUAL_TO_SOIL[law], kernel)
    assert abs(depth - soil_depths[kernel]) <= 1e-9 * soil_depths[kernel]
