"""Scenes, the runner that wires mesh -> fem_loads -> dynamics, results and the CLI.

The paper's scenes ship as TOML files in this folder; :func:`scene_path` finds them.
"""

from pathlib import Path

from .results import history_table, summary, write_outputs
from .runner import RunResult, initial_state, prepare_projectile, run_scene
from .scene import SceneError, apply_overrides, load_scene, scene_from_dict, scene_key
from .schema import Scene

__all__ = [
    "Scene", "SceneError", "load_scene", "scene_from_dict", "apply_overrides", "scene_key",
    "prepare_projectile", "initial_state", "run_scene", "RunResult",
    "history_table", "summary", "write_outputs", "scene_path", "SHIPPED_SCENES",
]

SCENE_DIR = Path(__file__).parent
SHIPPED_SCENES = sorted(p.stem for p in SCENE_DIR.glob("*.toml"))


def scene_path(name: str) -> Path:
    """Path of a shipped scene, e.g. ``scene_path("forrestal_luk_test2")``."""
    path = SCENE_DIR / f"{name.removesuffix('.toml')}.toml"
    if not path.exists():
        raise SceneError(f"no shipped scene {name!r}: the shipped scenes are {', '.join(SHIPPED_SCENES)}")
    return path
