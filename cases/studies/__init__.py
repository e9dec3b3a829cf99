"""Studies: many runs of a scene and what they show, a package per question: ``engine`` (sweeps, the pool, the one
threshold search, the report), ``speeds`` (the characteristic speeds measured, the ballistic limit, their guided
searches, stability maps), ``reduced`` (the reduced pitch-plane model, the load-only turn boundary), ``ensemble``,
``measured`` (test series, validation, law comparison, fits), ``numerics`` (accuracy, contact, entry), ``paper``.

Nothing imports it but the command line.  What it may import is written once, in pyproject.toml's
[tool.penetrate.rooms].
"""

from .engine.pool import Pool
from .engine.sweep import Sweep, SweepResult, Variation, end_cells, grid, parse_grid, read_variations, run_sweep
from .reduced.pitch_plane import Prediction, predict
from .speeds.characteristic import (
    ConvergentResult,
    CriticalSearch,
    find_critical_velocities,
    find_critical_velocity,
    measure_convergent_velocity,
)
from .speeds.instability import is_unstable

__all__ = [
    "Pool",
    "Sweep",
    "SweepResult",
    "Variation",
    "grid",
    "parse_grid",
    "read_variations",
    "run_sweep",
    "end_cells",
    "find_critical_velocity",
    "find_critical_velocities",
    "CriticalSearch",
    "measure_convergent_velocity",
    "ConvergentResult",
    "is_unstable",
    "predict",
    "Prediction",
]
