"""The compiled step of a run (``numerics.kernel = "compiled"``), with numba's cache named for its code.

The compiled step of the DAFL load (:mod:`.dafl_step`) inlines the Runge-Kutta step of
:mod:`dynamics.compiled_rk` (with the arithmetic of :mod:`dynamics.quaternion` and
:mod:`dynamics.integrators`) and calls the load kernel of :mod:`fem_loads.kernels.mesh_loop`; the reduced
pitch-plane trajectory of ``penetrate predict`` (:mod:`.pitch_plane_step`) inlines the driver of
:mod:`dynamics.pitch_plane` and calls the ring load of :mod:`fem_loads.kernels.rings`.  numba keeps the
machine code in the cache of the joining file and notices changes of that file alone, not of the
modules it inlines and calls.  So numba's cache lives in a folder named for the digest of all
these sources (:func:`compiled_sources`: the closure of the entry points' modules under their imports) and
numba's version, ``$PENETRATE_CACHE_DIR/numba/<digest>``
(``$NUMBA_CACHE_DIR/<digest>`` when that is set), set before any of them is imported: changed code gets a
folder of its own and
compiles afresh.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import hashlib
import json
import os
import sys
from collections.abc import Callable
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

import numpy as np

from .persistence import cache_dir, write_json

if TYPE_CHECKING:  # imported where used, after use_numba_cache
    from dynamics import RigidBody, RungeKutta
    from dynamics.compiled_rk import CompiledLoad, CompiledRungeKutta
    from fem_loads import DAFLLoads

__all__ = [
    "compiled_step",
    "compiled_load_function",
    "compiled_modules",
    "precompile",
    "numba_cache_folder",
    "use_numba_cache",
    "needs_compiling",
    "announce_compiling",
    "compiled_sources",
    "ENTRY_MODULES",
    "ENTRY_POINTS",
]

#: the modules that define each compiled entry point; what they inline and call is found from their imports
ENTRY_MODULES = ("cases.run.dafl_step", "cases.run.pitch_plane_step")
#: the packages of this project (imports of anything else are not followed)
PROJECT_PACKAGES = ("mesh", "fem_loads", "dynamics", "cases")
ROOT = Path(__file__).resolve().parents[2]


def _module_file(name: str, root: Path) -> Path | None:
    """The source file of project module ``name`` under ``root`` (found by path: importing a package to ask
    would run its ``__init__``, which may import compiled modules before numba's cache is set)."""
    base = root.joinpath(*name.split("."))
    return next((p for p in (base.with_suffix(".py"), base / "__init__.py") if p.is_file()), None)


def _imports(name: str, root: Path) -> list[tuple[str, list[str] | None]]:
    """``(module, names)`` of every project import in module ``name`` at run time (``None``: ``import module``),
    relative imports resolved, those under ``if TYPE_CHECKING:`` left out."""
    path = _module_file(name, root)
    assert path is not None
    package = name if path.name == "__init__.py" else name.rpartition(".")[0]
    found: list[tuple[str, list[str] | None]] = []

    class Visitor(ast.NodeVisitor):
        def visit_If(self, node: ast.If) -> None:
            if isinstance(node.test, ast.Name) and node.test.id == "TYPE_CHECKING":
                for child in node.orelse:
                    self.visit(child)
                return
            self.generic_visit(node)

        def visit_Import(self, node: ast.Import) -> None:
            found.extend((alias.name, None) for alias in node.names)

        def visit_ImportFrom(self, node: ast.ImportFrom) -> None:
            module = node.module or ""
            if node.level:
                parts = package.split(".")
                module = ".".join([*parts[: len(parts) - node.level + 1], *([module] if module else [])])
            found.append((module, [alias.name for alias in node.names]))

    Visitor().visit(ast.parse(path.read_text()))
    return [(module, names) for module, names in found if module.split(".")[0] in PROJECT_PACKAGES]


def compiled_sources(root: Path = ROOT) -> list[str]:
    """The project modules behind the compiled entry points: the closure of :data:`ENTRY_MODULES` under their
    imports.  A module is followed whole; a name imported from a package is followed to the module its
    ``__init__`` takes it from (the package's other modules are not what the compiled code uses).

    Parsing the modules to follow their imports takes a quarter of a second, which every process that loads the
    compiled step would pay: the closure is kept in the cache folder under the signature of the project's Python
    files (names, sizes and modification times), and found again while none of them changed."""
    signature = hashlib.sha256(str(root).encode())
    for package in PROJECT_PACKAGES:
        for path in sorted((root / package).rglob("*.py")):
            stat = path.stat()
            signature.update(f"{path.relative_to(root)}\0{stat.st_mtime_ns}\0{stat.st_size}\n".encode())
    return list(_kept_closure(root, signature.hexdigest()))


@functools.lru_cache(maxsize=8)
def _kept_closure(root: Path, signature: str) -> tuple[str, ...]:
    """:func:`compiled_sources` as kept for ``signature``, or found afresh and kept."""
    kept = cache_dir() / "numba" / f"sources-{hashlib.sha256(str(root).encode()).hexdigest()[:12]}.json"
    try:
        record = json.loads(kept.read_text())
        if record["signature"] == signature:
            return tuple(record["modules"])
    except (OSError, ValueError, KeyError, TypeError):
        pass  # none kept yet, or unreadable: find it
    modules = tuple(_closure(root))
    with contextlib.suppress(OSError):  # a read-only cache: found again next time
        write_json(kept, {"signature": signature, "modules": modules})
    return modules


def _closure(root: Path) -> list[str]:
    """The closure of :data:`ENTRY_MODULES` under their imports (:func:`compiled_sources`), found by parsing."""
    modules: set[str] = set()
    seen: set[tuple[str, tuple[str, ...] | None]] = set()
    parsed: dict[str, list[tuple[str, list[str] | None]]] = {}

    def imports(name: str) -> list[tuple[str, list[str] | None]]:
        if name not in parsed:
            parsed[name] = _imports(name, root)
        return parsed[name]

    todo: list[tuple[str, list[str] | None]] = [(name, None) for name in ENTRY_MODULES]
    while todo:
        module, names = todo.pop()
        path = _module_file(module, root)
        key = (module, None if names is None else tuple(names))
        if path is None or key in seen:
            continue
        seen.add(key)
        modules.add(module)
        if names is not None and path.name == "__init__.py":
            sources = {n: m for m, ns in imports(module) if ns for n in ns}
            for name in names:
                origin = sources.get(name)
                if _module_file(f"{module}.{name}", root):
                    todo.append((f"{module}.{name}", None))
                elif origin is not None:
                    whole = _module_file(f"{origin}.{name}", root) is not None
                    todo.append((f"{origin}.{name}", None) if whole else (origin, [name]))
                else:  # defined in the package's __init__ itself
                    todo.append((module, None))
            continue
        for imported, imported_names in imports(module):
            if imported_names is None:
                todo.append((imported, None))
                continue
            for name in imported_names:
                whole = _module_file(f"{imported}.{name}", root) is not None
                todo.append((f"{imported}.{name}", None) if whole else (imported, [name]))
    return sorted(modules)


@functools.cache
def _sources_digest(root: Path = ROOT) -> str:
    """The digest of the compiled sources (:func:`compiled_sources`) and numba's version, read once per process
    (the sources a process has imported do not change under it)."""
    import numba

    digest = hashlib.sha256(numba.__version__.encode())
    for name in compiled_sources(root):
        path = _module_file(name, root)
        assert path is not None
        digest.update(name.encode() + b"\0" + path.read_bytes())
    return digest.hexdigest()[:16]


def numba_cache_folder() -> Path:
    """``$PENETRATE_CACHE_DIR/numba/<digest of the compiled sources and numba's version>``."""
    root = os.environ.get("NUMBA_CACHE_DIR")
    return (Path(root) if root else cache_dir() / "numba") / _sources_digest()


@functools.cache
def use_numba_cache() -> None:
    """Point numba's cache at :func:`numba_cache_folder`, once per process, before any compiled module is
    imported (numba fixes a function's cache folder when its module defines it).  Once per process: a later
    call would find the folder set or the modules imported, after 6 ms of looking (the sources' signature)."""
    if not all(name in sys.modules for name in compiled_sources()):
        from numba import config

        config.CACHE_DIR = str(numba_cache_folder())  # type: ignore[attr-defined]  # set from the environment at import: numba's stubs omit it


#: each compiled entry point (a function numba caches): the module of this package that defines it, what it is,
#: and about how long numba takes to compile it (s, as measured on 2 cores; the time depends on the machine and on
#: what else runs), for the message a first compilation prints
ENTRY_POINTS = {
    "dafl_step": ("dafl_step", "the compiled step (the DAFL load inside the Runge-Kutta step)", "15-30"),
    "pitch_plane_trajectory": ("pitch_plane_step", "the reduced pitch-plane model (penetrate predict)", "15-25"),
    "pitch_plane_turns": (
        "pitch_plane_step",
        "the reduced pitch-plane model's batch of runs (the multi-fidelity sort)",
        "5-10",
    ),
}


def needs_compiling(entry: str) -> bool:
    """Whether numba's cache for this code version lacks the machine code of ``entry`` (a key of
    :data:`ENTRY_POINTS`) for this copy of the code: numba writes a function's index file when it first compiles
    it, in a folder named for the source's own folder (another checkout's code is not this one's)."""
    from numba.core.caching import _CacheLocator

    module = ENTRY_POINTS[entry][0]
    source = Path(__file__).with_name(f"{module}.py")
    folder = numba_cache_folder() / _CacheLocator.get_suitable_cache_subpath(str(source))
    return not any(folder.glob(f"{module}.{entry}-*.nbi"))


#: the entry points this process has looked for in the cache: the first call compiles or loads the machine
#: code, so a study's worker looks once, not once per run
_LOOKED_FOR: set[str] = set()


def announce_compiling(entry: str) -> None:
    """Say on stderr, before numba starts, that ``entry`` is about to be compiled and about how long it
    takes, when the cache lacks it (a first run after installing, or after the code changed); silent when
    the machine code is cached, as after ``./dev setup`` (``python -m cases.tools.warm``).  Looks once per
    process and entry point."""
    if entry in _LOOKED_FOR:
        return
    _LOOKED_FOR.add(entry)
    if needs_compiling(entry):
        _, what, seconds = ENTRY_POINTS[entry]
        print(
            f"penetrate: compiling {what} with numba, about {seconds} s, once for this version of the code"
            f" (kept in {numba_cache_folder()})",
            file=sys.stderr,
            flush=True,
        )


def _import_compiled() -> tuple[ModuleType, ModuleType]:
    use_numba_cache()
    from dynamics import compiled_rk as step
    from fem_loads.kernels import mesh_loop as load

    return step, load


def compiled_modules() -> tuple[ModuleType, ModuleType]:
    """``(dynamics.compiled_rk, fem_loads.kernels.mesh_loop)``, imported with numba's cache in
    :func:`numba_cache_folder`: for code that calls or times the compiled kernels itself (the load benchmark,
    docs/performance/loads.py)."""
    return _import_compiled()


def _dafl_step() -> Callable[..., None]:
    from .dafl_step import dafl_step

    return dafl_step


def compiled_load_function(loads: DAFLLoads, weight: np.ndarray | None = None) -> CompiledLoad:
    """The compiled form of a scene's ``loads`` (a ``DAFLLoads``; plus ``weight``, N, world frame, when given):
    the same load function, callable from Python, for code that evaluates loads without a run (the load-only
    turn boundary of ``penetrate paper``)."""
    announce_compiling("dafl_step")
    step, load = _import_compiled()
    return step.CompiledLoad(load.dafl_kernel, load.kernel_data(loads), _dafl_step(), weight)


def compiled_step(
    loads: DAFLLoads, method: RungeKutta, body: RigidBody, weight: np.ndarray | None
) -> tuple[CompiledLoad, CompiledRungeKutta, Callable[..., float]]:
    """The compiled load, Runge-Kutta step and exit height for a scene's loads (a ``DAFLLoads``).

    Returns ``(load, method, lowest_height)``: a :class:`~dynamics.compiled_rk.CompiledLoad` (plus
    ``weight``, N, world frame, when given), the :class:`~dynamics.compiled_rk.CompiledRungeKutta` of
    ``method``, and ``lowest_height(position, attitude, face=None)`` for the exit events
    (:meth:`fem_loads.DAFLLoads.lowest_height`).
    """
    compiled_load = compiled_load_function(loads, weight)
    step, load = _import_compiled()
    from dynamics.quaternion import rotation_matrix
    from fem_loads.kernels.layout import DATA_EFFECTS
    from fem_loads.target import FrontFace

    data = compiled_load.data
    compiled_method = step.CompiledRungeKutta(method)
    _warm(compiled_load, compiled_method, body, data, load.lowest_height_kernel)
    facing: dict[FrontFace, tuple[np.ndarray, ...]] = {}

    def lowest_height(position: np.ndarray, attitude: np.ndarray, face: FrontFace | None = None) -> float:
        if face is not None and face not in facing:  # the kernel's arrays with this face in the effects record
            effects = data[DATA_EFFECTS].copy()
            effects["face_normal"], effects["face_offset"] = face.normal, face.offset
            facing[face] = data[:DATA_EFFECTS] + (effects,) + data[DATA_EFFECTS + 1 :]
        return load.lowest_height_kernel(data if face is None else facing[face], position, rotation_matrix(attitude))

    return compiled_load, compiled_method, lowest_height


def _warm(
    load: CompiledLoad,
    method: CompiledRungeKutta,
    body: RigidBody,
    data: tuple[np.ndarray, ...],
    lowest_height: Callable[[tuple[np.ndarray, ...], np.ndarray, np.ndarray], float],
) -> None:
    """Call every compiled function once, far above the target (no load), so that numba's loading (or first
    compiling) is done before a run starts its clock: a run's ``integration_time`` is the integration alone."""
    from dynamics import State

    far = State(0.0, np.array([0.0, 0.0, 1e6]), np.array([0.0, 0.0, -1.0]), np.array([1.0, 0.0, 0.0, 0.0]), np.zeros(3))
    method.step(body, load, far, 1e-9)
    lowest_height(data, far.position, far.rotation)


def precompile() -> None:
    """Compile (or load) the compiled step once, on a four-point stand-in surface.

    The machine code does not depend on the surface: a process that calls this before it starts
    workers (the test session does) compiles once, and the workers load the code from the cache
    instead of compiling it side by side.
    """
    from dynamics import RK4, RigidBody
    from fem_loads import DAFLLoads, ResistanceLaw, SurfaceQuadrature

    points = np.array([[0.1, 0.05, 0.05], [0.1, -0.05, 0.05], [0.1, 0.05, -0.05], [0.1, -0.05, -0.05]])
    normals = points / np.linalg.norm(points, axis=1)[:, None]
    loads = DAFLLoads(
        SurfaceQuadrature(points, normals, np.full(4, 1e-4)),
        ResistanceLaw(1e6, 1e3),
        contact_incidence=0.005,
        entry_smoothing=4.0,
    )
    compiled_step(loads, RK4(), RigidBody(1.0, np.eye(3)), None)
