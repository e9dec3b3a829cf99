"""Mass properties and surface quadrature (scikit-fem), resistance laws and DAFL loads.

Knows nothing of time integration; it integrates over the profile and the mesh of ``mesh``.
What it may import is written once, in pyproject.toml's [tool.penetrate.rooms].
"""

from .dafl import DAFLLoads, SurfaceStress
from .mass import MassProperties, mass_properties, to_skfem
from .quadrature import NORMAL_MODELS, SurfaceQuadrature, find_mirror_images, surface_quadrature
from .resistance import NAMED_LAWS, ResistanceLaw, UnknownLawError, resistance_law

__all__ = [
    "MassProperties",
    "mass_properties",
    "to_skfem",
    "SurfaceQuadrature",
    "surface_quadrature",
    "find_mirror_images",
    "NORMAL_MODELS",
    "ResistanceLaw",
    "NAMED_LAWS",
    "resistance_law",
    "UnknownLawError",
    "DAFLLoads",
    "SurfaceStress",
]
