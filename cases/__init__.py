"""Everything above the physics, in rooms: scene, run, studies, viz and the command line.

The shipped scenes are the TOML files in this folder; :func:`scene_path` finds them.
"""

from pathlib import Path

SCENE_DIR = Path(__file__).parent
SHIPPED_SCENES = sorted(p.stem for p in SCENE_DIR.glob("*.toml"))


def scene_path(name: str) -> Path:
    """Path of a shipped scene, e.g. ``scene_path("forrestal_luk_test2")``."""
    from .scene import SceneError

    path = SCENE_DIR / f"{name.removesuffix('.toml')}.toml"
    if not path.exists():
        raise SceneError(f"no shipped scene {name!r}: the shipped scenes are {', '.join(SHIPPED_SCENES)}")
    return path
