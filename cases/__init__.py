"""Everything above the physics, in rooms: ``scene``, ``run``, ``studies``, ``viz`` and the command line ``cli``.

Imports flow one way, from the command line down to the scene; the rooms, their jobs and what each may
import are written once, in pyproject.toml's [tool.penetrate.rooms] (docs/architecture.md prints the
table).  The shipped scenes are the TOML files
in this folder; :func:`scene_path` finds them.  The names below are the short public API; they are
imported on first use, so ``import cases`` costs nothing.
"""

from __future__ import annotations

import importlib
from pathlib import Path

SCENE_DIR = Path(__file__).parent
SHIPPED_SCENES = sorted(p.stem for p in SCENE_DIR.glob("*.toml"))

_EXPORTS = {
    "Scene": "scene",
    "SceneError": "scene",
    "InputError": "scene",
    "load_scene": "scene",
    "run_scene": "run",
    "RunResult": "run",
    "RunSummary": "run",
    "summarise": "run",
    "history_table": "run",
    "write_outputs": "run",
    "prepare_projectile": "run",
}
__all__ = ["scene_path", "SHIPPED_SCENES", *_EXPORTS]


def scene_path(name: str) -> Path:
    """Path of a shipped scene, e.g. ``scene_path("forrestal_luk_test2")``."""
    path = SCENE_DIR / f"{name.removesuffix('.toml')}.toml"
    if not path.exists():
        from .scene import SceneError

        raise SceneError(f"no shipped scene {name!r}: the shipped scenes are {', '.join(SHIPPED_SCENES)}")
    return path


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f".{_EXPORTS[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
