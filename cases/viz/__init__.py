"""Pictures of runs: the resistance field on the surface, off-screen pyvista frames and animations,
ParaView files, matplotlib panels, and the one way figures are made and saved.

It takes every stress from the run's own load function (``DAFLLoads.surface_stress``) and evaluates
no physics of its own.  What it may import is written once, in pyproject.toml's [tool.penetrate.rooms].
"""

from .field import (
    INSTANT_NAMES,
    FieldEvaluator,
    SurfaceField,
    SurfaceMesh,
    key_instants,
    resolve_instants,
    surface_mesh,
)
from .figures import new_figure, save_figure, subplots
from .render import render_all

__all__ = [
    "FieldEvaluator",
    "SurfaceField",
    "SurfaceMesh",
    "surface_mesh",
    "key_instants",
    "resolve_instants",
    "INSTANT_NAMES",
    "render_all",
    "new_figure",
    "subplots",
    "save_figure",
]
