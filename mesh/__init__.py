"""Projectile geometry and meshing (gmsh, meshio). Knows nothing of forces or time.

What it may import is written once, in pyproject.toml's [tool.penetrate.rooms]."""

from .files import build_file_mesh, place_file_body
from .geometry import BODY, COUNTERWEIGHT, OUTER, ProjectileMesh, build_mesh
from .imported import BodyOutline, FileGeometry, GeometryError, body_frame
from .io import read_mesh, write_mesh
from .placement import AxisymmetricMassProperties, analytic_mass_properties, place_counterweight
from .profile import (
    BluntOgiveNose,
    ConeNose,
    Interior,
    OgiveNose,
    Profile,
    ProfileBody,
    ProfileNose,
    ProjectileGeometry,
    SecantOgiveNose,
)

__all__ = [
    "Profile",
    "OgiveNose",
    "ConeNose",
    "SecantOgiveNose",
    "BluntOgiveNose",
    "ProfileNose",
    "ProfileBody",
    "Interior",
    "ProjectileGeometry",
    "ProjectileMesh",
    "build_mesh",
    "BODY",
    "COUNTERWEIGHT",
    "OUTER",
    "read_mesh",
    "write_mesh",
    "FileGeometry",
    "GeometryError",
    "BodyOutline",
    "build_file_mesh",
    "place_file_body",
    "body_frame",
    "AxisymmetricMassProperties",
    "analytic_mass_properties",
    "place_counterweight",
]
