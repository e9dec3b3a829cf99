"""One formula, one place: the resistance law, each factor of a point's stress (the smooth step, the contact, entry
and free-surface factors, the friction stress and its slip factor, the exposure) and Newton-Euler are each defined
once, as a scalar function that the numpy path evaluates and numba compiles, and no module reads another's
private attributes.

How this is kept: every compiled form is checked to *be* numba's compilation of the one definition (its
``py_func`` is that function object), made in one module and imported from there by every kernel, so a compiled
module that wrote its own copy would fail here; the smooth step may be called only by the factors (a ramp
written anywhere else is another copy of one); a friction cap is taken in one function; the smooth step's
coefficients (6, 15, 10) may appear in one function only; and no ``x._name`` is read outside ``self`` and
``cls``.  Each structural check has a control that it finds a copy.
"""

from __future__ import annotations

import ast
import functools
import subprocess
import sys
from collections.abc import Callable
from pathlib import Path

import pytest

from cases.run.compiled import compiled_modules

ROOT = Path(__file__).resolve().parents[2]
PACKAGES = ("mesh", "fem_loads", "dynamics", "cases", "docs")
compiled_modules()  # numba's cache in the folder named for the compiled code

#: the compiled forms :mod:`fem_loads.kernels.native` makes, and the module of each one definition
NATIVE = {
    "slip_factor": ("target", "slip_factor_scalars"),
    "slip": ("target", "slip_scalars"),
    "builtin_stress": ("resistance", "normal_stress_scalars"),
    "polynomial_stress": ("resistance", "polynomial_stress_scalars"),
    "entry_factor": ("factors", "entry_factor_scalars"),
    "friction_stress": ("factors", "friction_stress_scalars"),
    "point_stress": ("factors", "point_stress_scalars"),
    "switches": ("factors", "switches_scalars"),
    "face_frame": ("target", "face_frame_scalars"),
    "cube_cell": ("exposure", "cube_cell_scalars"),
    "cell_exposure": ("exposure", "cell_exposure_scalars"),
}
#: compiled functions of :mod:`fem_loads.kernels.native` with no plain twin (they read the kernels' records)
NATIVE_ONLY = ("law_stress", "call_user_law")
#: the functions that may call the smooth step: the factors
RAMP_CALLERS = [
    "fem_loads/factors.py:contact_factor_scalars",
    "fem_loads/factors.py:entry_factor_scalars",
    "fem_loads/factors.py:surface_factor_scalars",
]


def _definitions() -> list[tuple[object, object]]:
    """(compiled form, the one definition) pairs."""
    import importlib

    from dynamics import compiled_rk as compiled_step
    from dynamics import pitch_plane, rigid_body
    from fem_loads.kernels import native

    pairs = [
        (getattr(native, name), getattr(importlib.import_module(f"fem_loads.{module}"), function))
        for name, (module, function) in NATIVE.items()
    ]
    return pairs + [
        (compiled_step._euler_scalars, rigid_body.euler_scalars),
        (pitch_plane._euler_scalars, rigid_body.euler_scalars),
    ]


@pytest.mark.parametrize("index", range(len(NATIVE) + 2))
def test_each_compiled_form_is_the_one_definition(index):
    compiled, definition = _definitions()[index]
    assert getattr(compiled, "py_func", None) is definition, (compiled, definition)


@pytest.mark.parametrize("module", ["mesh_loop", "point", "rings"])
def test_the_kernels_take_every_compiled_form_from_one_module(module):
    """A kernel's ``point_stress`` (and every other name :mod:`fem_loads.kernels.native` makes) is native's own
    object."""
    import importlib

    from fem_loads.kernels import native

    kernel = importlib.import_module(f"fem_loads.kernels.{module}")
    shared = [name for name in (*NATIVE, *NATIVE_ONLY) if hasattr(kernel, name)]
    assert shared, module
    assert all(getattr(kernel, name) is getattr(native, name) for name in shared)


def test_the_coefficients_keep_one_order_from_the_law_to_the_loops():
    """``COEFFICIENTS`` is the order of :func:`normal_stress_scalars`' parameters; the law, its packed record and the
    tuple the compiled loops unpack (``law_values``) hold each coefficient in that place (six distinct values)."""
    import inspect

    from fem_loads.kernels import native
    from fem_loads.kernels.records import pack_laws
    from fem_loads.resistance import COEFFICIENTS, ResistanceLaw, normal_stress_scalars

    assert COEFFICIENTS == ("c0", "k", "c1", "c2", "c", "n")
    assert tuple(inspect.signature(normal_stress_scalars).parameters)[2:8] == COEFFICIENTS
    law = ResistanceLaw(1e6, 2e3, k=3e5, c1=4e4, c=5e2, n=1.5)
    assert law.coefficients == (1e6, 3e5, 4e4, 2e3, 5e2, 1.5)
    records = pack_laws(law)[0]
    assert tuple(float(records[0][name]) for name in COEFFICIENTS) == law.coefficients
    assert native.law_values(records[0])[0] == law.coefficients


def test_a_numpy_run_reads_no_kernel_record_and_loads_no_numba():
    """The numpy load takes its effects from :func:`fem_loads.dafl.effect_values`, not from the kernels' records: a
    run on numpy imports neither the kernels nor numba (a fresh process, so that nothing else has)."""
    code = (
        "import sys\n"
        "from cases import load_scene, run_scene, scene_path\n"
        "run_scene(load_scene(scene_path('forrestal_luk_test2'), {'numerics.kernel': 'numpy'}))\n"
        "print(sorted(m for m in sys.modules if m.startswith(('fem_loads.kernels', 'numba'))))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, cwd=ROOT, check=True)
    assert done.stdout.strip() == "[]", done.stdout


def test_the_numpy_path_calls_the_same_definitions():
    """The numpy path's names are the definitions themselves (or thin array wrappers around them)."""
    from dynamics import rigid_body
    from fem_loads import dafl, factors, resistance, target

    assert dafl.point_stress_scalars is factors.point_stress_scalars
    assert dafl.switches_scalars is factors.switches_scalars
    assert dafl.slip_factor_scalars is target.slip_factor_scalars
    assert target.layer_share_scalars is factors.layer_share_scalars
    assert target.surface_factor_scalars is factors.surface_factor_scalars
    assert target.free_face_distance_scalars is factors.free_face_distance_scalars
    assert target.friction_stress_scalars is factors.friction_stress_scalars
    assert "normal_stress_scalars(" in Path(resistance.__file__).read_text().split("def normal_stress(", 1)[1]
    assert "euler_scalars(" in Path(rigid_body.__file__).read_text().split("def accelerations(", 1)[1]


@functools.cache
def _parse(source: str) -> ast.Module:
    """``ast.parse(source)``, once a source: each check walks every module of the project (the trees are read,
    never changed)."""
    return ast.parse(source)


def _modules() -> list[Path]:
    return [path for package in PACKAGES for path in sorted((ROOT / package).rglob("*.py"))]


def _holders(finder: Callable[[str], list[str]]) -> list[str]:
    """``module path:function`` of every function of the project that ``finder`` finds in its module's source."""
    return [f"{path.relative_to(ROOT)}:{name}" for path in _modules() for name in finder(path.read_text())]


def test_the_smooth_step_s_coefficients_appear_in_one_function():
    """``t^3 (10 - 15 t + 6 t^2)``: any function holding the constants 6, 15 and 10 is another copy of it."""
    holders = []
    for path in _modules():
        for node in ast.walk(_parse(path.read_text())):
            if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
                numbers = {
                    c.value for c in ast.walk(node) if isinstance(c, ast.Constant) and isinstance(c.value, float)
                }
                if {6.0, 15.0, 10.0} <= numbers:
                    holders.append(f"{path.relative_to(ROOT)}:{node.name}")
    assert holders == ["fem_loads/factors.py:smooth_step_scalars"], holders


def _functions_calling(tree: ast.AST, names: set[str]) -> list[ast.FunctionDef]:
    """The innermost functions of ``tree`` that call one of ``names`` (a bare name or an attribute)."""
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.FunctionDef | ast.AsyncFunctionDef):
            nested = [n for child in node.body for n in ast.walk(child) if isinstance(n, ast.FunctionDef)]
            inner = {id(n) for function in nested for n in ast.walk(function)}
            calls = [
                n
                for child in node.body
                for n in ast.walk(child)
                if isinstance(n, ast.Call) and id(n) not in inner and _called_name(n) in names
            ]
            if calls:
                found.append(node)
    return found


def _names(*nodes: ast.AST) -> set[str]:
    """The names and attribute names anywhere in ``nodes``."""
    found = {n.id for node in nodes for n in ast.walk(node) if isinstance(n, ast.Name)}
    return found | {n.attr for node in nodes for n in ast.walk(node) if isinstance(n, ast.Attribute)}


def _called_name(call: ast.Call) -> str:
    function = call.func
    return function.attr if isinstance(function, ast.Attribute) else getattr(function, "id", "")


def _ramp_callers(source: str) -> list[str]:
    return [f.name for f in _functions_calling(_parse(source), {"smooth_step", "smooth_step_scalars"})]


def _cap_takers(source: str) -> list[str]:
    """Functions taking a minimum with a name that holds ``cap``: a friction cap."""
    found = []
    for function in _functions_calling(_parse(source), {"min", "minimum"}):
        for call in ast.walk(function):
            is_min = isinstance(call, ast.Call) and _called_name(call) in ("min", "minimum")
            if is_min and any("cap" in name for name in _names(*call.args)):
                found.append(function.name)
                break
    return found


def test_only_the_factors_call_the_smooth_step():
    """A ramp (contact, entry, interface, free surface) is a factor of :mod:`fem_loads.factors`; a call of the smooth
    step anywhere else writes one of them again."""
    holders = _holders(_ramp_callers)
    assert sorted(holders) == RAMP_CALLERS, holders


def test_a_friction_cap_is_taken_in_one_function():
    holders = _holders(_cap_takers)
    assert holders == ["fem_loads/factors.py:friction_stress_scalars"], holders


def _width_writers(source: str) -> list[str]:
    """Functions multiplying a name that holds ``incidence``: the contact width ``W = w + delta U`` written out."""
    functions = [n for n in ast.walk(_parse(source)) if isinstance(n, ast.FunctionDef | ast.AsyncFunctionDef)]
    found = []
    for function in functions:
        products = [n for n in ast.walk(function) if isinstance(n, ast.BinOp) and isinstance(n.op, ast.Mult)]
        if any("incidence" in name for name in _names(*products)):
            found.append(function.name)
    return found


def test_the_contact_width_is_written_in_one_function():
    """``W = w + delta U`` for every load (numpy, mesh kernel, rings) and the 1-D reference, and a control: a
    width written out in a kernel is found."""
    holders = _holders(_width_writers)
    assert holders == ["fem_loads/factors.py:contact_width_scalars"], holders
    assert _width_writers("def load(e, u):\n    return e.contact_width + e.contact_incidence * u\n") == ["load"]


def _separation_writers(source: str) -> list[str]:
    """Functions taking ``max(Vn, 0)`` of a normal velocity: the law's velocity under separation written out."""
    found = []
    for function in _functions_calling(_parse(source), {"max", "maximum"}):
        for call in ast.walk(function):
            if isinstance(call, ast.Call) and _called_name(call) in ("max", "maximum"):
                names = {a.id for a in call.args if isinstance(a, ast.Name)}  # the velocity itself, not a sum
                zero = any(isinstance(a, ast.Constant) and a.value == 0.0 for a in call.args)
                if zero and names & {"normal_velocity", "vn"}:
                    found.append(function.name)
                    break
    return found


def test_the_law_s_velocity_under_separation_is_taken_in_one_function():
    """``max(Vn, 0)`` for every load (numpy, mesh kernel, rings), and a control: one written in a kernel is found."""
    holders = _holders(_separation_writers)
    assert holders == ["fem_loads/factors.py:law_velocity_scalars"], holders
    assert _separation_writers("def law(vn, c0):\n    return c0 + max(vn, 0.0)\n") == ["law"]


def test_the_factor_checks_find_a_copy():
    """Control: a contact ramp, an entry ramp, a free-surface factor and a friction cap written in a kernel are
    each found."""
    copies = {
        "contact": "def load(vn, w):\n    return smooth_step(vn / w) * 2.0\n",
        "entry": "def load(z, l):\n    return native.smooth_step(0.5 - z / l)\n",
        "surface": "def load(z, d, f):\n    return f + (1.0 - f) * smooth_step_scalars(z / d)\n",
    }
    for source in copies.values():
        assert _ramp_callers(source) == ["load"]
    assert _cap_takers("def tau(s, mu, cap):\n    return min(mu * s, cap)\n") == ["tau"]
    assert _cap_takers("def tau(s, f):\n    return np.minimum(f.coefficient * s, f.cap)\n") == ["tau"]
    assert _ramp_callers("def load(vn):\n    return contact_factor(vn, True, 1.0, 0.0, 0.0)\n") == []


def _switches_builders(source: str) -> list[str]:
    return [f.name for f in _functions_calling(_parse(source), {"Switches"})]


def test_the_switches_are_built_from_the_effects_in_one_function():
    """Every load's :class:`~fem_loads.factors.Switches` come from ``switches_scalars`` (numpy, mesh kernel, rings)."""
    holders = _holders(_switches_builders)
    assert holders == ["fem_loads/factors.py:switches_scalars"], holders
    # control: a kernel that builds its own is found
    assert _switches_builders("def setup(e):\n    return factors.Switches(True, True, 0.0)\n") == ["setup"]


#: the loads: each multiplies a point's law value by its factors through the pipeline, point_stress_scalars
LOADS = ("fem_loads/dafl.py", "fem_loads/kernels/point.py", "fem_loads/kernels/rings.py")
#: the factors the pipeline applies (the entry factor is also the layers' blend, and the rings' early exit)
PIPELINE_FACTORS = {"contact_factor", "contact_factor_scalars", "surface_factor", "surface_factor_scalars"}


def _factor_callers(source: str) -> list[str]:
    return [f.name for f in _functions_calling(_parse(source), PIPELINE_FACTORS)]


def _pipeline_callers(source: str) -> list[str]:
    return [f.name for f in _functions_calling(_parse(source), {"point_stress", "point_stress_scalars"})]


@pytest.mark.parametrize("module", LOADS)
def test_every_load_multiplies_its_factors_in_the_one_pipeline(module):
    """The numpy load, the compiled kernel's points and the rings call :func:`fem_loads.factors.point_stress_scalars`
    (or its compiled form) and apply no contact or free-surface factor of their own."""
    source = (ROOT / module).read_text()
    assert _pipeline_callers(source), module
    assert _factor_callers(source) == [], module


def test_the_pipeline_check_finds_a_factor_applied_outside_it():
    """Control: a kernel that multiplies by the contact factor itself is found, and one that calls the pipeline is
    seen calling it."""
    own = "def sums(vn, w):\n    return law(vn) * contact_factor(vn, True, 1.0 / w, 0.0, 0.0)\n"
    assert _factor_callers(own) == ["sums"] and _pipeline_callers(own) == []
    shared = "def sums(vn, z, s):\n    return native.point_stress(law(vn), vn, -z, z, 0.0, s)\n"
    assert _factor_callers(shared) == [] and _pipeline_callers(shared) == ["sums"]


def test_no_module_reads_another_s_private_attributes():
    """``x._name`` only on ``self`` and ``cls`` (argparse's sub-parsers action has no public name for its type)."""
    found = []
    for path in _modules():
        for node in ast.walk(_parse(path.read_text())):
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
    tree = _parse(source)
    functions = [n for n in ast.walk(tree) if isinstance(n, ast.FunctionDef)]
    numbers = {c.value for c in ast.walk(functions[0]) if isinstance(c, ast.Constant)}
    assert {6.0, 15.0, 10.0} <= numbers
    private = [n for n in ast.walk(tree) if isinstance(n, ast.Attribute) and n.attr.startswith("_")]
    assert [ast.unparse(n) for n in private] == ["loads._weights"]
