"""Studies: many runs of a scene and what they show (sweeps, characteristic speeds, their prediction by a reduced
model and the searches it guides, stability maps, ensembles, accuracy, law comparisons, the paper).

Nothing imports it but the command line.  What it may import is written once, in pyproject.toml's
[tool.penetrate.rooms].
"""

from .pool import Pool
from .predict import Prediction, predict
from .speeds import (
    ConvergentResult,
    CriticalSearch,
    find_critical_velocities,
    find_critical_velocity,
    is_unstable,
    measure_convergent_velocity,
)
from .sweep import Sweep, SweepResult, Variation, end_cells, grid, parse_grid, read_variations, run_sweep

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
