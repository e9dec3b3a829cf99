"""The scene: what a scene file may say, how it is read and overridden, and the physics objects it describes.

A scene knows no runs; each spec builds its own physics object (``NoseSpec.build()``,
``LawSpec.build()``, ``Projectile.shape()``, ``Scene.loads()``).  What it may import is written once, in
pyproject.toml's [tool.penetrate.rooms].

The errors are imported with the package; the other names below on first use, so that
``from cases.scene import InputError`` (every command of the command line, before it knows whether
it will read a scene) costs nothing, while the schema brings numpy, pydantic and the physics.
"""

from __future__ import annotations

from typing import TYPE_CHECKING, Any

from .errors import InputError, SceneError, one_line

if TYPE_CHECKING:  # the names imported on first use (__getattr__), for the type checker
    from .load import (
        Overrides,
        apply_overrides,
        dotted_key,
        load_scene,
        parse_override,
        read_scene_data,
        read_toml,
        scene_from_dict,
        scene_key,
    )
    from .projectile import Projectile
    from .schema import Impact, Numerics, Outputs, Scene
    from .target import Effects, Target, build_law

_EXPORTS = {
    "Scene": "schema",
    "Impact": "schema",
    "Numerics": "schema",
    "Outputs": "schema",
    "Projectile": "projectile",
    "Target": "target",
    "Effects": "target",
    "build_law": "target",
    "load_scene": "load",
    "scene_from_dict": "load",
    "apply_overrides": "load",
    "dotted_key": "load",
    "parse_override": "load",
    "read_toml": "load",
    "read_scene_data": "load",
    "scene_key": "load",
    "Overrides": "load",
}

__all__ = [
    "Scene",
    "Projectile",
    "Target",
    "Effects",
    "Impact",
    "Numerics",
    "Outputs",
    "build_law",
    "load_scene",
    "scene_from_dict",
    "apply_overrides",
    "dotted_key",
    "parse_override",
    "read_toml",
    "read_scene_data",
    "scene_key",
    "Overrides",
    "InputError",
    "SceneError",
    "one_line",
]


def __getattr__(name: str) -> Any:
    if name in _EXPORTS:
        # the import statement's machinery (not importlib.import_module), so that -X importtime lists the module
        value = getattr(__import__(f"{__name__}.{_EXPORTS[name]}", fromlist=[name]), name)
        globals()[name] = value  # found directly from now on
        return value
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
