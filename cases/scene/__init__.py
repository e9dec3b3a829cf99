"""The scene: what a scene file may say, how it is read and overridden, and the physics objects it describes.

A scene knows no runs: this room imports ``mesh`` and ``fem_loads`` (each spec builds its own
physics object: ``NoseSpec.build()``, ``LawSpec.build()``, ``Projectile.geometry()``,
``Scene.loads()``) and nothing else of ``cases``.
"""

from .errors import InputError, SceneError, one_line
from .load import (Overrides, apply_overrides, dotted_key, load_scene, parse_override, read_toml, scene_from_dict,
                   scene_key)
from .projectile import Projectile
from .schema import Impact, Numerics, Outputs, Scene
from .target import Effects, Target, build_law

__all__ = [
    "Scene", "Projectile", "Target", "Effects", "Impact", "Numerics", "Outputs", "build_law",
    "load_scene", "scene_from_dict", "apply_overrides", "dotted_key", "parse_override", "read_toml", "scene_key",
    "Overrides",
    "InputError", "SceneError", "one_line",
]
