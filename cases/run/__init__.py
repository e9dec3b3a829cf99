"""One run of a scene: prepare the projectile, integrate, summarise, and keep it on disk.

A run knows no studies or pictures.  What it may import is written once, in pyproject.toml's [tool.penetrate.rooms].
"""

from .history import (
    CONVERGENCE_THRESHOLD,
    HISTORY_UNITS,
    attack_angle_peak,
    convergence_speed,
    history_columns,
    history_table,
)
from .persistence import (
    ContentCache,
    RunStore,
    atomic_write,
    atomic_write_text,
    cache_dir,
    code_version,
    json_text,
    write_json,
)
from .prepare import PreparedProjectile, body_mesh, cached_mesh, prepare_projectile
from .runner import RunResult, impact_positions, initial_attitude, initial_state, run_scene
from .summary import RunSummary, StoredRun, summarise, write_outputs

__all__ = [
    "prepare_projectile",
    "PreparedProjectile",
    "cached_mesh",
    "body_mesh",
    "run_scene",
    "RunResult",
    "initial_state",
    "initial_attitude",
    "impact_positions",
    "history_table",
    "history_columns",
    "attack_angle_peak",
    "convergence_speed",
    "HISTORY_UNITS",
    "CONVERGENCE_THRESHOLD",
    "RunSummary",
    "summarise",
    "write_outputs",
    "StoredRun",
    "RunStore",
    "ContentCache",
    "atomic_write",
    "atomic_write_text",
    "write_json",
    "json_text",
    "cache_dir",
    "code_version",
]
