"""A resistance law of the user's own: a Python function in a file, run by the numpy path and compiled.

The function is ``def name(normal_velocity, depth, p1, p2, ...)``: the normal stress (Pa) at the normal velocity
``Vn`` (m/s, positive into the target) and the depth ``z`` (m below the target surface), with the law's parameters
after them, evaluated at ``Vn >= 0`` only with separation (without, the load clips it at zero).  :func:`user_law`
checks it before a run starts, each failure one line (:class:`LawError`); docs/laws.md (Your own law) says what it
may use and what is checked.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.util
import inspect
import math
import sys
import warnings
from collections.abc import Callable, Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

__all__ = ["UserLaw", "user_law", "LawError", "MAX_PARAMETERS", "PROBE_SPEEDS", "PROBE_DEPTHS"]

MAX_PARAMETERS = 8  # the compiled kernel passes the parameters as this many floats
#: the probe grid (m/s, m): a law must give finite stresses >= 0 on all of it
PROBE_SPEEDS = (0.0, 0.5, 1.0, 10.0, 100.0, 300.0, 1000.0, 3000.0)
PROBE_DEPTHS = (-0.01, 0.0, 0.01, 0.1, 1.0, 10.0, 100.0)


class LawError(ValueError):
    """A user law that cannot be used; the message is one line naming what to change."""


@dataclass(frozen=True, eq=False)
class UserLaw:
    """A user's resistance function with its parameters.

    Attributes
    ----------
    source : str
        ``"path/to/file.py:name"`` as given (the path absolute).
    parameters : tuple of (str, float)
        The parameters in the function's order.
    function : callable
        The plain Python function.
    sha256 : str
        The digest of the file the function was read from.
    """

    source: str
    parameters: tuple[tuple[str, float], ...]
    function: Callable[..., Any]
    sha256: str

    @property
    def name(self) -> str:
        return self.source.rsplit(":", 1)[1]

    #: a user law may depend on depth: the load evaluates depths everywhere
    depth_dependent = True

    def normal_stress(self, normal_velocity: np.ndarray, depth: np.ndarray | float = 0.0) -> np.ndarray:
        """The function on arrays (``Vn`` in m/s, depth in m), broadcast to the shape of ``normal_velocity``."""
        normal_velocity = np.asarray(normal_velocity, dtype=float)
        values = self.function(normal_velocity, depth, **dict(self.parameters))
        return np.array(np.broadcast_to(np.asarray(values, dtype=float), normal_velocity.shape))

    @property
    def parameter_values(self) -> np.ndarray:
        """The parameters as the compiled kernel takes them: :data:`MAX_PARAMETERS` floats, zeros after the last."""
        values = np.zeros(MAX_PARAMETERS)
        values[: len(self.parameters)] = [value for _, value in self.parameters]
        return values

    def compiled(self) -> Any:
        """The numba ``cfunc`` of ``(Vn, z, p_1 .. p_8) -> sigma``, compiled once per process and law file."""
        return _compile(self.source, self.sha256, len(self.parameters))


@functools.cache  # once per process, file and digest: a study builds many scenes of one law
def _read_function(path: str, name: str, digest: str) -> Callable[..., Any]:
    module_name = f"penetrate_user_law_{digest[:16]}"
    spec = importlib.util.spec_from_file_location(module_name, path)
    if spec is None or spec.loader is None:
        raise LawError(f"function = '{path}:{name}': not a Python file (give a .py file)")
    module = importlib.util.module_from_spec(spec)
    try:
        spec.loader.exec_module(module)
    except Exception as exc:  # the user's file: any error in it is theirs to fix
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
        raise LawError(
            f"function = '{path}:{name}': the file does not run ({type(exc).__name__}: {first}); it must"
            " import without error"
        ) from None
    sys.modules[module_name] = module  # numba finds a function's globals through its module
    function = getattr(module, name, None)
    if not inspect.isfunction(function):
        raise LawError(
            f"function = '{path}:{name}': the file defines no function {name!r} (give the name of a function"
            " defined in it)"
        )
    return function


def user_law(source: str, parameters: Mapping[str, float], folder: Path | None = None) -> UserLaw:
    """The law ``"file.py:name"`` with its ``parameters``, checked (see the module); a relative file is found
    in ``folder`` (default: the working directory).  Raises :class:`LawError`."""
    file, separator, name = source.rpartition(":")
    if not separator or not file or not name.isidentifier():
        raise LawError(f"function = {source!r}: give 'path/to/file.py:name' (a file and a function in it)")
    path = Path(file).expanduser()
    if not path.is_absolute():
        path = (folder or Path.cwd()) / path
    try:
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
    except OSError as exc:
        raise LawError(
            f"function = {source!r}: cannot read {path} ({exc.strerror or exc}); give a readable .py file, absolute"
            " or relative to the scene file's folder"
        ) from None
    shown = f"{path}:{name}"
    function = _read_function(str(path.resolve()), name, digest)
    law = UserLaw(f"{path.resolve()}:{name}", _parameters(function, shown, parameters), function, digest)
    _probe(law, shown)
    return law


def _parameters(
    function: Callable[..., Any], shown: str, parameters: Mapping[str, float]
) -> tuple[tuple[str, float], ...]:
    """The parameters in the function's order; refuses a signature that does not fit them."""
    arguments = list(inspect.signature(function).parameters.values())
    positional = (inspect.Parameter.POSITIONAL_ONLY, inspect.Parameter.POSITIONAL_OR_KEYWORD)
    if len(arguments) < 2 or any(argument.kind not in positional for argument in arguments):
        raise LawError(
            f"function = '{shown}': must be def {function.__name__}(normal_velocity, depth, p1, p2, ...),"
            " plain arguments only"
        )
    names = [argument.name for argument in arguments[2:]]
    if unknown := sorted(set(parameters) - set(names)):
        raise LawError(f"parameters: {', '.join(unknown)} unknown to '{shown}' (allowed: {', '.join(names) or 'none'})")
    if missing := [name for name in names if name not in parameters]:
        raise LawError(f"parameters: '{shown}' needs {', '.join(missing)} (give parameters = {{...}})")
    if len(names) > MAX_PARAMETERS:
        raise LawError(f"function = '{shown}': {len(names)} parameters, at most {MAX_PARAMETERS} allowed")
    for name in names:
        value = parameters[name]
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not math.isfinite(value):
            raise LawError(f"parameters.{name} = {value!r}: must be a finite number")
    return tuple((name, float(parameters[name])) for name in names)


def _probe(law: UserLaw, shown: str) -> None:
    """Refuses a law that is not finite and >= 0 on the probe grid, does not compile, or compiles to other numbers."""
    speeds, depths = np.meshgrid(PROBE_SPEEDS, PROBE_DEPTHS, indexing="ij")
    with np.errstate(all="ignore"):
        try:
            plain = law.normal_stress(speeds, depths)
        except Exception as exc:
            first = str(exc).strip().splitlines()[0] if str(exc).strip() else ""
            raise LawError(
                f"function = '{shown}': fails on arrays of Vn and depth ({type(exc).__name__}: {first}); it must"
                " take arrays: write it with numpy's functions (np.maximum, np.where), which take floats too"
            ) from None
    bad = ~(np.isfinite(plain) & (plain >= 0.0))
    if bad.any():
        i, j = np.argwhere(bad)[0]
        raise LawError(
            f"function = '{shown}': gives {plain[i, j]:g} Pa at Vn = {speeds[i, j]:g} m/s, depth {depths[i, j]:g} m"
            " (allowed: finite stresses >= 0)"
        )
    try:
        compiled = law.compiled()
    except Exception as exc:
        first = str(exc).strip().splitlines()[0] if str(exc).strip() else type(exc).__name__
        raise LawError(
            f"function = '{shown}': numba cannot compile it ({first}); it must use arithmetic and numpy's functions"
            " on floats only"
        ) from None
    values = law.parameter_values
    for i, j in np.ndindex(speeds.shape):
        fast = compiled(speeds[i, j], depths[i, j], *values)
        if not abs(fast - plain[i, j]) <= 1e-9 * max(abs(plain[i, j]), 1.0):
            raise LawError(
                f"function = '{shown}': compiled, it gives {fast:g} Pa at Vn = {speeds[i, j]:g} m/s, depth"
                f" {depths[i, j]:g} m, and {plain[i, j]:g} Pa on arrays (it must give the same numbers: use numpy's"
                " functions, not Python's)"
            )


@functools.cache
def _compile(source: str, digest: str, count: int) -> Any:
    """``cfunc`` of the law with its parameters as :data:`MAX_PARAMETERS` floats (the unused ones ignored)."""
    from numba import cfunc, njit, types  # numba imported here: a scene that names no user law needs none
    from numba.core.errors import NumbaExperimentalFeatureWarning

    path, name = source.rsplit(":", 1)
    function = njit(error_model="numpy")(_read_function(path, name, digest))
    arguments = ", ".join(f"p{k}" for k in range(MAX_PARAMETERS))
    passed = ", ".join(f"p{k}" for k in range(count))
    namespace: dict[str, Any] = {"law": function}
    exec(  # the parameters by position: the kernel's signature is fixed
        f"def stress(normal_velocity, depth, {arguments}):\n"
        f"    return law(normal_velocity, depth{', ' if count else ''}{passed})\n",
        namespace,
    )
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", NumbaExperimentalFeatureWarning)
        signature = types.float64(*([types.float64] * (2 + MAX_PARAMETERS)))  # (Vn, z, p_1 .. p_8) -> sigma
        return cfunc(signature, error_model="numpy")(namespace["stress"])
