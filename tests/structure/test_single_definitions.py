"""One formula, one place: the resistance law, the smooth step, the slip factor and Newton-Euler are each defined
once, as a scalar function that the numpy path evaluates and numba compiles, and no module reads another's
private attributes.

How this is kept: every compiled form is checked to *be* numba's compilation of the one definition (its
``py_func`` is that function object), so a compiled module that wrote its own copy would fail here; the smooth
step's coefficients (6, 15, 10) may appear in one function only; and no ``x._name`` is read outside ``self`` and
``cls``.
"""

from __future__ import annotations

import ast
from pathlib import Path

import pytest

from cases.run.compiled import compiled_modules

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("mesh", "fem_loads", "dynamics", "cases", "docs")
compiled_modules()  # numba's cache in the folder named for the compiled code


def _definitions() -> list[tuple[object, object]]:
    """(compiled form, the one definition) pairs."""
    from dynamics import compiled as compiled_step
    from dynamics import pitch_plane, rigid_body
    from fem_loads import compiled, compiled_point, exposure, native, ramps, resistance, revolved, target

    return [
        (native.smooth_step, ramps.smooth_step_scalars),
        (native.slip_factor, target.slip_factor_scalars),
        (native.builtin_stress, resistance.normal_stress_scalars),
        (native.polynomial_stress, resistance.polynomial_stress_scalars),
        (compiled.smooth_step, ramps.smooth_step_scalars),
        (compiled_point.slip_factor, target.slip_factor_scalars),
        (compiled_point.builtin_stress, resistance.normal_stress_scalars),
        (compiled.polynomial_stress, resistance.polynomial_stress_scalars),
        (revolved.smooth_step, ramps.smooth_step_scalars),
        (revolved.slip_factor, target.slip_factor_scalars),
        (revolved.builtin_stress, resistance.normal_stress_scalars),
        (native.cube_cell, exposure.cube_cell_scalars),
        (compiled_step._euler_scalars, rigid_body.euler_scalars),
        (pitch_plane._euler_scalars, rigid_body.euler_scalars),
    ]


@pytest.mark.parametrize("index", range(14))
def test_each_compiled_form_is_the_one_definition(index):
    compiled, definition = _definitions()[index]
    assert getattr(compiled, "py_func", None) is definition, (compiled, definition)


def test_the_numpy_path_calls_the_same_definitions():
    """The numpy path's names are the definitions themselves (or thin array wrappers around them)."""
    from dynamics import rigid_body
    from fem_loads import dafl, ramps, resistance, target

    assert dafl.smooth_step_scalars is ramps.smooth_step_scalars
    assert dafl.slip_factor_scalars is target.slip_factor_scalars
    assert "normal_stress_scalars(" in Path(resistance.__file__).read_text().split("def normal_stress(", 1)[1]
    assert "euler_scalars(" in Path(rigid_body.__file__).read_text().split("def accelerations(", 1)[1]


def _modules() -> list[Path]:
    return [path for package in PACKAGES for path in sorted((ROOT / package).rglob("*.py"))]


def test_the_smooth_step_s_coefficients_appear_in_one_function():
    """``t^3 (10 - 15 t + 6 t^2)``: any function holding the constants 6, 15 and 10 is another copy of it."""
    holders = []
    for path in _modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                numbers = {
                    c.value for c in ast.walk(node) if isinstance(c, ast.Constant) and isinstance(c.value, float)
                }
                if {6.0, 15.0, 10.0} <= numbers:
                    holders.append(f"{path.relative_to(ROOT)}:{node.name}")
    assert holders == ["fem_loads/ramps.py:smooth_step_scalars"], holders


def test_no_module_reads_another_s_private_attributes():
    """``x._name`` only on ``self`` and ``cls`` (argparse's sub-parsers action has no public name for its type)."""
    found = []
    for path in _modules():
        for node in ast.walk(ast.parse(path.read_text())):
            if not (isinstance(node, ast.Attribute) and node.attr.startswith("_") and not node.attr.startswith("__")):
                continue
            if isinstance(node.value, ast.Name) and node.value.id in ("self", "cls"):
                continue
            if ast.unparse(node) == "argparse._SubParsersAction":
                continue
            found.append(f"{path.relative_to(ROOT)}:{node.lineno}: {ast.unparse(node)}")
    assert not found, "\n".join(found)


def test_the_check_finds_a_copy():
    """Control: a function with the smooth step's coefficients, and a private read, are found."""
    source = "def step(t):\n    return t * t * t * (10.0 + t * (6.0 * t - 15.0))\n\nvalue = loads._weights\n"
    tree = ast.parse(source)
    functions = [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)]
    numbers = {c.value for c in ast.walk(functions[0]) if isinstance(c, ast.Constant)}
    assert {6.0, 15.0, 10.0} <= numbers
    private = [n for n in ast.walk(tree) if isinstance(n, ast.Attribute) and n.attr.startswith("_")]
    assert [ast.unparse(n) for n in private] == ["loads._weights"]
