"""Mass properties and surface quadrature (scikit-fem), resistance laws and DAFL loads.

Knows nothing of time integration; imports ``mesh`` (the profile and the mesh it integrates over),
never ``dynamics`` or ``cases``.
"""

from .dafl import DAFLLoads, SurfaceStress
from .mass import MassProperties, mass_properties, to_skfem
from .quadrature import NORMAL_MODELS, SurfaceQuadrature, mirror_quarters, surface_quadrature
from .resistance import NAMED_LAWS, ResistanceLaw, UnknownLawError, resistance_law

__all__ = [
    "MassProperties",
    "mass_properties",
    "to_skfem",
    "SurfaceQuadrature",
    "surface_quadrature",
    "mirror_quarters",
    "NORMAL_MODELS",
    "ResistanceLaw",
    "NAMED_LAWS",
    "resistance_law",
    "UnknownLawError",
    "DAFLLoads",
    "SurfaceStress",
]
