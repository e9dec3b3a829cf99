"""Prepare a scene's projectile: its mesh, mass properties and surface quadrature, computed once and cached.

The mesh (gmsh), the scikit-fem mass properties and the outer-surface
quadrature depend only on the projectile and four numerics keys
(:func:`preparation_key`); they are kept in memory (per process) and on disk
(:class:`~.persistence.ContentCache` under ``$PENETRATE_CACHE_DIR``), so a
later run of the same projectile reads them back without meshing, assembling
or importing gmsh and scikit-fem.
"""

from __future__ import annotations

import dataclasses
import functools
import io
import zipfile
from dataclasses import dataclass

import numpy as np

from fem_loads import MassProperties, SurfaceQuadrature, mass_properties, surface_quadrature, to_skfem
from mesh import Profile, ProjectileGeometry, ProjectileMesh, build_mesh, read_mesh, write_mesh

from ..scene import Numerics, Projectile, Scene
from .persistence import ContentCache, atomic_path, atomic_write, cache_dir

__all__ = ["PreparedProjectile", "prepare_projectile", "preparation_key", "cached_mesh", "prepared_path"]


@dataclass(frozen=True)
class PreparedProjectile:
    """Everything about a projectile that a run needs, computed once."""

    geometry: ProjectileGeometry
    mass: MassProperties
    quadrature: SurfaceQuadrature
    n_tetra: int

    @property
    def profile(self) -> Profile:
        return self.geometry.profile

    @property
    def tip(self) -> np.ndarray:
        """The nose tip relative to the centre of mass, body frame (m)."""
        return -self.mass.centre


def cached_mesh(geometry: ProjectileGeometry, size: float, order: int = 2) -> ProjectileMesh:
    """The mesh of ``geometry`` at element size ``size`` (m), from the cache when it was made before.

    A sweep therefore meshes each projectile once.  Writes are atomic, so concurrent
    workers at worst mesh the same projectile twice; a corrupt entry is meshed again.
    """
    inputs = {"geometry": dataclasses.asdict(geometry), "nose": type(geometry.profile.nose).__name__, "size": size,
              "order": order}
    path = ContentCache(cache_dir()).path("mesh", inputs, ".vtu")
    if path.exists():
        try:
            return read_mesh(path)
        except Exception:
            path.unlink(missing_ok=True)
    mesh = build_mesh(geometry, size, order)
    with atomic_path(path) as tmp:
        write_mesh(mesh, tmp)
    return mesh


def preparation_key(scene: Scene) -> tuple[str, str]:
    """What a prepared projectile depends on: the projectile and the mesh and quadrature numerics (JSON)."""
    return (scene.projectile.model_dump_json(),
            scene.numerics.model_dump_json(include={"mesh_size", "geometry_order", "normals", "quadrature_order"}))


def prepare_projectile(scene: Scene) -> PreparedProjectile:
    """Mesh, mass properties and surface quadrature of a scene's projectile (cached; see the module)."""
    return _prepare(*preparation_key(scene))


def prepared_path(spec_json: str, numerics_json: str):
    """The cache file of the prepared arrays of a :func:`preparation_key`."""
    return ContentCache(cache_dir()).path("prepared", {"projectile": spec_json, "numerics": numerics_json}, ".npz")


@functools.lru_cache(maxsize=16)
def _prepare(spec_json: str, numerics_json: str) -> PreparedProjectile:
    spec = Projectile.model_validate_json(spec_json)
    numerics = Numerics.model_validate_json(numerics_json)
    path = prepared_path(spec_json, numerics_json)
    if path.exists() and (prepared := _load(path, spec)) is not None:
        return prepared
    prepared = _compute(spec, numerics, spec.geometry())
    _save(path, prepared)
    return prepared


def _load(path, spec: Projectile) -> PreparedProjectile | None:
    try:
        with np.load(path) as data:
            # the counterweight's span as placed when this entry was computed: the same floats, without
            # placing it again
            span = data["counterweight"]
            geometry = spec.geometry(placed=(float(span[0]), float(span[1])) if span.size else None)
            mass = MassProperties(float(data["mass"]), data["centre"], data["inertia"], float(data["volume"]))
            quarters = data["mirror_quarters"]
            quadrature = SurfaceQuadrature(data["points"], data["normals"], data["weights"],
                                           quarters if quarters.size else None)
            return PreparedProjectile(geometry, mass, quadrature, int(data["n_tetra"]))
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        path.unlink(missing_ok=True)  # a corrupt entry: compute again
        return None


def _save(path, prepared: PreparedProjectile) -> None:
    m, q = prepared.mass, prepared.quadrature
    buffer = io.BytesIO()
    span = prepared.geometry.counterweight
    np.savez(buffer, mass=m.mass, centre=m.centre, inertia=m.inertia, volume=m.volume, points=q.points,
             normals=q.normals, weights=q.weights, n_tetra=prepared.n_tetra,
             counterweight=np.array(span if span is not None else [], dtype=float),
             mirror_quarters=q.mirror_quarters if q.mirror_quarters is not None else np.empty(0, dtype=np.int64))
    atomic_write(path, buffer.getvalue())


def _compute(spec: Projectile, numerics: Numerics, geometry: ProjectileGeometry) -> PreparedProjectile:
    """Mesh, scikit-fem mass properties and outer-surface quadrature.

    Raises
    ------
    RuntimeError
        gmsh could not mesh the projectile at ``numerics.mesh_size``, or
        scikit-fem could not map its curved elements (very slender noses and
        thin walls meshed coarsely); the one-line message names the field.
    ValueError
        ``projectile.transverse_inertia_scale`` makes an inertia tensor no rigid body has.
    """
    size = f"numerics.mesh_size = {numerics.mesh_size:g}"
    try:
        mesh = cached_mesh(geometry, numerics.mesh_size, numerics.geometry_order)
    except Exception as exc:  # gmsh raises bare Exceptions ("HXT 3D mesh failed", ...)
        raise RuntimeError(f"{size}: gmsh could not mesh this projectile at this size ({exc});"
                           " a finer numerics.mesh_size usually works") from exc
    try:
        fem_mesh = to_skfem(mesh)
        mass = _mass_properties(spec, mesh, fem_mesh)
        quadrature = surface_quadrature(mesh, mass.centre, geometry.profile, numerics.normals,
                                        numerics.quadrature_order, fem_mesh)
    except Exception as exc:  # scikit-fem: "Newton iteration didn't converge" on distorted curved elements
        raise RuntimeError(f"{size}: the elements of this mesh are too distorted to integrate ({exc});"
                           " a finer numerics.mesh_size, or numerics.geometry_order = 1, usually works") from exc
    return PreparedProjectile(geometry, _scaled_inertia(spec, mass), quadrature, len(mesh.tetra))


def _mass_properties(spec: Projectile, mesh: ProjectileMesh, fem_mesh) -> MassProperties:
    """Given, or integrated over the mesh (a homogeneous body of a given mass has its density scaled)."""
    if spec.mass_properties is not None:
        given = spec.mass_properties
        return MassProperties.axisymmetric(given.mass, given.centre_of_mass, given.axial_inertia,
                                           given.transverse_inertia)
    mass = mass_properties(mesh, spec.densities(), fem_mesh)
    if spec.mass is not None and spec.counterweight is None:
        scale = spec.mass / mass.mass
        mass = MassProperties(spec.mass, mass.centre, mass.inertia * scale, mass.volume)
    return mass


def _scaled_inertia(spec: Projectile, mass: MassProperties) -> MassProperties:
    """``projectile.transverse_inertia_scale`` applied, refusing tensors no rigid body has."""
    if spec.transverse_inertia_scale == 1.0:
        return mass
    axial, transverse = mass.axial_inertia, mass.transverse_inertia
    lowest = 0.5 * axial / transverse  # I_axial <= 2 I_transverse for every rigid body
    if spec.transverse_inertia_scale < lowest:
        raise ValueError(f"projectile.transverse_inertia_scale = {spec.transverse_inertia_scale:g}: the transverse"
                         f" moments ({spec.transverse_inertia_scale * transverse:.3g} kg m^2) would be less than"
                         f" half the axial moment ({axial:.3g} kg m^2), which no rigid body has (allowed for this"
                         f" projectile: transverse_inertia_scale >= {lowest:.3g})")
    return mass.with_transverse_scale(spec.transverse_inertia_scale)
