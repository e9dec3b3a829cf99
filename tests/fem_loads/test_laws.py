"""Resistance functions, defined once: each family against its closed form on arrays and compiled, a user's
law read from a file and checked before any run, each failure one line."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from numba import njit

import cases
from fem_loads.resistance import ResistanceLaw, normal_stress_scalars, resistance_law
from fem_loads.user_law import LawError, user_law

LAWS = Path(cases.__file__).parent / "laws" / "soil_laws.py"
SPEEDS = np.array([0.0, 0.3, 1.0, 47.0, 300.0, 1200.0])
DEPTHS = np.array([-0.01, 0.0, 0.2, 1.0, 3.5, 40.0])
compiled_stress = njit(normal_stress_scalars)

FAMILIES = {
    "cavity expansion": (
        resistance_law("soil"),
        lambda v, z: 1.718 * 10e6 + 1.227 * 1860.0 * v**2,
    ),
    "polynomial": (ResistanceLaw(3e6, 900.0, c1=2.5e4), lambda v, z: 3e6 + 2.5e4 * v + 900.0 * v**2),
    "power": (ResistanceLaw(4e6, 0.0, c=5e3, n=1.6), lambda v, z: 4e6 + 5e3 * v**1.6),
    "depth gradient": (
        ResistanceLaw(3e6, 1e3, k=2e6),
        lambda v, z: 3e6 + 2e6 * max(z, 0.0) + 1e3 * v**2,
    ),
    "table": (
        ResistanceLaw(3e6, 1e3, strength_table=((0.0, 0.0), (1.0, 5e6), (3.0, 6e6))),
        lambda v, z: 3e6 + float(np.interp(z, [0.0, 1.0, 3.0], [0.0, 5e6, 6e6])) + 1e3 * v**2,
    ),
}


@pytest.mark.parametrize("family", list(FAMILIES))
def test_each_family_is_its_closed_form_on_arrays_and_compiled(family):
    law, closed_form = FAMILIES[family]
    speeds, depths = np.meshgrid(SPEEDS, DEPTHS, indexing="ij")
    expected = np.vectorize(closed_form)(speeds, depths)
    np.testing.assert_allclose(law.normal_stress(speeds, depths), expected, rtol=1e-13)
    for v, z, value in zip(speeds.ravel(), depths.ravel(), expected.ravel()):
        assert compiled_stress(v, z, *law.coefficients, *law.table) == pytest.approx(value, rel=1e-13)


def test_receding_elements_see_the_odd_extension():
    """Without separation a receding element (Vn < 0) feels the strength less the velocity terms."""
    law = ResistanceLaw(3e6, 900.0, c1=2.5e4, c=5e3, n=1.6)
    v = np.array([-20.0, 20.0])
    stress = law.normal_stress(v, 0.0)
    assert stress[0] == pytest.approx(3e6 - (stress[1] - 3e6), rel=1e-13)


@pytest.mark.parametrize(
    ("field", "value"),
    [("c0", -1.0), ("c2", math.nan), ("c1", -2.0), ("n", 0.0), ("n", 11.0)],
)
def test_coefficients_out_of_range_are_refused(field, value):
    with pytest.raises(ValueError, match=f"^{field} = "):
        ResistanceLaw(**{"c0": 1e6, "c2": 1e3, field: value})


def test_a_user_law_equal_to_the_built_in_one_gives_its_numbers_on_both_paths():
    soil = resistance_law("soil")
    law = user_law(f"{LAWS}:cavity_expansion", {"c2": soil.c2, "c0": soil.c0})
    assert [name for name, _ in law.parameters] == ["c0", "c2"]  # the function's order, not the table's
    speeds, depths = np.meshgrid(SPEEDS, DEPTHS, indexing="ij")
    np.testing.assert_allclose(law.normal_stress(speeds, depths), soil.normal_stress(speeds, depths), rtol=1e-15)
    compiled = law.compiled()
    for v, z in zip(speeds.ravel(), depths.ravel()):
        assert compiled(v, z, *law.parameter_values) == pytest.approx(float(soil.normal_stress(v, z)), rel=1e-15)


def test_a_relative_law_file_is_found_in_the_given_folder():
    law = user_law("laws/soil_laws.py:cavity_expansion", {"c0": 1.0, "c2": 1.0}, LAWS.parent.parent)
    assert law.source == f"{LAWS}:cavity_expansion"


BAD_LAWS = {
    "no function named": ("laws.py", {}, "give 'path/to/file.py:name'"),
    "missing file": ("nowhere.py:f", {}, "cannot read"),
    "not defined": ("{file}:absent", {}, "defines no function 'absent'"),
    "file raises": ("{broken}:f", {}, "the file does not run (ZeroDivisionError"),
    "one argument": ("{file}:one_argument", {}, "must be def one_argument(normal_velocity, depth"),
    "keyword arguments": ("{file}:keywords", {"c0": 1.0}, "plain arguments only"),
    "unknown parameter": ("{file}:constant", {"c0": 1.0, "c9": 2.0}, "c9 unknown to"),
    "missing parameter": ("{file}:constant", {}, "needs c0"),
    "not a number": ("{file}:constant", {"c0": "1"}, "parameters.c0 = '1': must be a finite number"),
    "too many": ("{file}:nine", dict.fromkeys("abcdefghi", 1.0), "9 parameters, at most 8"),
    "negative": ("{file}:constant", {"c0": -1.0}, "gives -1 Pa at Vn = 0 m/s"),
    "not finite": ("{file}:inverse", {}, "gives inf Pa at Vn = 0 m/s"),
    "python only": ("{file}:python_max", {}, "fails on arrays of Vn and depth"),
    "not compiled": ("{file}:text", {}, "numba cannot compile it"),
}
SOURCE = """
import numpy as np

def one_argument(normal_velocity):
    return normal_velocity

def keywords(normal_velocity, depth, *, c0):
    return c0

def constant(normal_velocity, depth, c0):
    return c0 + 0.0 * normal_velocity

def nine(normal_velocity, depth, a, b, c, d, e, f, g, h, i):
    return a + 0.0 * normal_velocity

def inverse(normal_velocity, depth):
    return 1.0 / normal_velocity

def python_max(normal_velocity, depth):
    return max(normal_velocity, 0.0)

def text(normal_velocity, depth):
    return np.asarray(float(str(1.0))) + 0.0 * normal_velocity
"""


@pytest.mark.parametrize("case", list(BAD_LAWS))
def test_an_unusable_user_law_is_one_line_naming_what_to_change(tmp_path, case):
    (tmp_path / "laws.py").write_text(SOURCE)
    (tmp_path / "broken.py").write_text("1 / 0\n")
    source, parameters, message = BAD_LAWS[case]
    source = source.format(file=tmp_path / "laws.py", broken=tmp_path / "broken.py")
    with np.errstate(all="ignore"), pytest.raises(LawError) as error:
        user_law(source, parameters, tmp_path)
    text = str(error.value)
    assert message in text and "\n" not in text, text
