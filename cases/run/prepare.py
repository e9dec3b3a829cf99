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
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from fem_loads import MassProperties, SurfaceQuadrature, mass_properties, surface_quadrature, to_skfem
from fem_loads.exposure import Exposure
from fem_loads.quadrature import with_exposure
from mesh import Profile, ProjectileGeometry, ProjectileMesh, build_mesh, read_mesh, write_mesh
from mesh.cad import CadSurface
from mesh.files import build_file_mesh, place_file_body
from mesh.geometry import outer_triangles
from mesh.imported import BodyOutline, FileGeometry, GeometryError, body_frame, outline

from ..scene import InputError, Numerics, Projectile, Scene
from .persistence import ContentCache, atomic_path, atomic_write, cache_dir

if TYPE_CHECKING:  # scikit-fem is imported where it is used (fem_loads.mass)
    from skfem import MeshTet1, MeshTet2

__all__ = ["PreparedProjectile", "prepare_projectile", "preparation_key", "cached_mesh", "body_mesh", "prepared_path"]


@dataclass(frozen=True)
class PreparedProjectile:
    """Everything about a projectile that a run needs, computed once.

    ``outline``: a file's body measured on its mesh (None for the analytic projectiles,
    whose :attr:`profile` states it).
    """

    geometry: ProjectileGeometry | FileGeometry
    mass: MassProperties
    quadrature: SurfaceQuadrature
    n_tetra: int
    outline: BodyOutline | None = None

    @property
    def profile(self) -> Profile:
        """The exact profile of an analytic projectile (a file's body has none)."""
        if isinstance(self.geometry, FileGeometry):
            raise InputError(
                "this needs an axisymmetric profile, and the projectile comes from"
                f" {self.geometry.path}: it works for the analytic projectiles only"
            )
        return self.geometry.profile

    @property
    def length(self) -> float:
        """Tip to tail (m)."""
        return self.outline.length if self.outline is not None else self.profile.length

    @property
    def diameter(self) -> float:
        """Largest diameter (m)."""
        return self.outline.diameter if self.outline is not None else self.profile.diameter

    @property
    def nose_length(self) -> float:
        """Tip to where the body first reaches its largest radius (m)."""
        return self.outline.nose_length if self.outline is not None else self.profile.nose_length

    @property
    def tip(self) -> np.ndarray:
        """The nose tip relative to the centre of mass, body frame (m)."""
        return -self.mass.centre


def cached_mesh(geometry: ProjectileGeometry | FileGeometry, size: float, order: int = 2) -> ProjectileMesh:
    """The mesh of ``geometry`` at element size ``size`` (m), from the cache when it was made before.

    A sweep therefore meshes each projectile once.  Writes are atomic, so concurrent
    workers at worst mesh the same projectile twice; a corrupt entry is meshed again.
    A file's projectile is cached in its model frame (:func:`body_mesh` moves it).
    """
    if isinstance(geometry, FileGeometry):  # the file's digest is in the key: a changed file is meshed again
        inputs = {"file": dataclasses.asdict(geometry), "size": size, "order": order}
    else:
        inputs = {
            "geometry": dataclasses.asdict(geometry),
            "nose": type(geometry.profile.nose).__name__,
            "size": size,
            "order": order,
        }
    path = ContentCache(cache_dir()).path("mesh", inputs, ".vtu")
    if path.exists():
        try:
            return read_mesh(path)
        except Exception:
            path.unlink(missing_ok=True)
    if isinstance(geometry, FileGeometry):
        mesh = build_file_mesh(geometry, size, order)
    else:
        mesh = build_mesh(geometry, size, order)
    with atomic_path(path) as tmp:
        write_mesh(mesh, tmp)
    return mesh


def body_mesh(geometry: ProjectileGeometry | FileGeometry, size: float, order: int = 2) -> tuple[ProjectileMesh, float]:
    """The cached mesh in the body frame (tip at the origin) and the model frame's x of the tip (m; 0 for the
    analytic projectiles, which are meshed in the body frame)."""
    mesh = cached_mesh(geometry, size, order)
    return body_frame(mesh) if isinstance(geometry, FileGeometry) else (mesh, 0.0)


def preparation_key(scene: Scene) -> tuple[str, str]:
    """What a prepared projectile depends on: the projectile and the mesh and quadrature numerics (JSON)."""
    return (
        scene.projectile.model_dump_json(),
        scene.numerics.model_dump_json(include={"mesh_size", "geometry_order", "normals", "quadrature_order"}),
    )


def prepare_projectile(scene: Scene) -> PreparedProjectile:
    """Mesh, mass properties and surface quadrature of a scene's projectile (cached; see the module)."""
    return _prepare(*preparation_key(scene))


def prepared_path(spec_json: str, numerics_json: str) -> Path:
    """The cache file of the prepared arrays of a :func:`preparation_key`."""
    return ContentCache(cache_dir()).path("prepared", {"projectile": spec_json, "numerics": numerics_json}, ".npz")


@functools.lru_cache(maxsize=16)
def _prepare(spec_json: str, numerics_json: str) -> PreparedProjectile:
    spec = Projectile.model_validate_json(spec_json)
    numerics = Numerics.model_validate_json(numerics_json)
    path = prepared_path(spec_json, numerics_json)
    if path.exists() and (prepared := _load(path, spec)) is not None:
        return prepared
    prepared = _compute(spec, numerics, spec.shape())
    _save(path, prepared)
    return prepared


def _load(path: Path, spec: Projectile) -> PreparedProjectile | None:
    try:
        with np.load(path) as data:
            # the counterweight's span as placed when this entry was computed: the same floats, without
            # placing it again
            span = data["counterweight"]
            geometry = spec.shape(placed=(float(span[0]), float(span[1])) if span.size else None)
            mass = MassProperties(float(data["mass"]), data["centre"], data["inertia"], float(data["volume"]))
            images = data["mirror_images"]
            quadrature = SurfaceQuadrature(
                data["points"], data["normals"], data["weights"], images if images.size else None, _exposure(data)
            )
            sizes = data["outline"]
            body = BodyOutline(*(float(v) for v in sizes)) if sizes.size else None
            if isinstance(geometry, FileGeometry):  # placed as when this entry was computed
                axis, origin = (data[k].astype(float) for k in ("file_axis", "file_origin"))
                geometry = dataclasses.replace(
                    geometry,
                    axis=(float(axis[0]), float(axis[1]), float(axis[2])),
                    origin=(float(origin[0]), float(origin[1]), float(origin[2])),
                )
            return PreparedProjectile(geometry, mass, quadrature, int(data["n_tetra"]), body)
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        path.unlink(missing_ok=True)  # a corrupt entry: compute again
        return None


def _save(path: Path, prepared: PreparedProjectile) -> None:
    m, q = prepared.mass, prepared.quadrature
    buffer = io.BytesIO()
    span = getattr(prepared.geometry, "counterweight", None)
    arrays: dict[str, Any] = {
        "mirror_images": q.mirror_images if q.mirror_images is not None else np.empty(0, dtype=np.int64),
        **_exposure_arrays(q.exposure),
    }
    if isinstance(prepared.geometry, FileGeometry):
        arrays.update(file_axis=np.array(prepared.geometry.axis), file_origin=np.array(prepared.geometry.centre))
    np.savez(
        buffer,
        mass=m.mass,
        centre=m.centre,
        inertia=m.inertia,
        volume=m.volume,
        points=q.points,
        normals=q.normals,
        weights=q.weights,
        n_tetra=prepared.n_tetra,
        counterweight=np.array(span if span is not None else [], dtype=float),
        outline=np.array(dataclasses.astuple(prepared.outline) if prepared.outline else [], dtype=float),
        **arrays,
    )
    atomic_write(path, buffer.getvalue())


def _exposure_arrays(exposure: Exposure | None) -> dict[str, np.ndarray]:
    """The exposure's arrays for the cache file, its table as bits (an eighth of the bytes); none for None."""
    if exposure is None:
        return {"exposure_columns": np.empty(0, dtype=np.int64)}
    return {
        "exposure_columns": exposure.columns,
        "exposure_shape": np.array(exposure.table.shape),
        "exposure_bits": np.packbits(exposure.table.ravel()),
        "exposure_refined": exposure.refined,
    }


def _exposure(data: Any) -> Exposure | None:
    """The exposure kept by :func:`_exposure_arrays` (an ``np.load`` of the cache file)."""
    columns = data["exposure_columns"]
    if not columns.size:
        return None
    shape = tuple(int(n) for n in data["exposure_shape"])
    table = np.unpackbits(data["exposure_bits"], count=int(np.prod(shape))).reshape(shape)
    return Exposure(columns, table, data["exposure_refined"])


def _compute(spec: Projectile, numerics: Numerics, geometry: ProjectileGeometry | FileGeometry) -> PreparedProjectile:
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
    from_file = isinstance(geometry, FileGeometry)
    try:
        if isinstance(geometry, FileGeometry):  # its axis and origin from the body, wherever the file puts it
            geometry = place_file_body(geometry)
        mesh, tip = body_mesh(geometry, numerics.mesh_size, numerics.geometry_order)
    except GeometryError as exc:  # the file, not the numerics: bad input
        raise InputError(str(exc)) from None
    except Exception as exc:  # gmsh raises bare Exceptions ("HXT 3D mesh failed", ...)
        raise RuntimeError(
            f"{size}: gmsh could not mesh this projectile at this size ({exc});"
            " a finer numerics.mesh_size usually works"
        ) from exc
    if from_file and mesh.order != numerics.geometry_order:  # a mesh file's order is its own
        raise InputError(
            f"numerics.geometry_order = {numerics.geometry_order}: the mesh file has"
            f" {'10' if mesh.order == 2 else '4'}-node tetrahedra; set numerics.geometry_order ="
            f" {mesh.order}"
        )
    exact_cad = from_file and numerics.normals == "exact"
    try:
        fem_mesh = to_skfem(mesh)
        mass = _mass_properties(spec, mesh, fem_mesh)
        quadrature = surface_quadrature(
            mesh,
            mass.centre,
            None if isinstance(geometry, FileGeometry) else geometry.profile,
            numerics.normals,
            numerics.quadrature_order,
            fem_mesh,
            surface=CadSurface(geometry, tip) if exact_cad and isinstance(geometry, FileGeometry) else None,
            facet_rule="shape" if from_file else "basis",
        )
    except Exception as exc:  # scikit-fem: "Newton iteration didn't converge" on distorted curved elements
        raise RuntimeError(
            f"{size}: the elements of this mesh are too distorted to integrate ({exc});"
            " a finer numerics.mesh_size, or numerics.geometry_order = 1, usually works"
        ) from exc
    # rays start at most a twentieth of an element off the surface (beyond the split facets' sag from it), each
    # point's by its own sag; flat facets have no sag but dents between them, and take the whole twentieth
    lift = 0.05 * numerics.mesh_size
    quadrature = with_exposure(
        quadrature, outer_triangles(mesh) - mass.centre, lift, least_lift=lift if mesh.order == 1 else None
    )
    return PreparedProjectile(
        geometry, _scaled_inertia(spec, mass), quadrature, len(mesh.tetra), outline(mesh) if from_file else None
    )


def _mass_properties(spec: Projectile, mesh: ProjectileMesh, fem_mesh: MeshTet1 | MeshTet2) -> MassProperties:
    """Given, or integrated over the mesh (a homogeneous body of a given mass has its density scaled)."""
    if spec.mass_properties is not None:
        given = spec.mass_properties
        return MassProperties.axisymmetric(
            given.mass, given.centre_of_mass, given.axial_inertia, given.transverse_inertia
        )
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
        raise ValueError(
            f"projectile.transverse_inertia_scale = {spec.transverse_inertia_scale:g}: the transverse"
            f" moments ({spec.transverse_inertia_scale * transverse:.3g} kg m^2) would be less than"
            f" half the axial moment ({axial:.3g} kg m^2), which no rigid body has (allowed for this"
            f" projectile: transverse_inertia_scale >= {lowest:.3g})"
        )
    return mass.with_transverse_scale(spec.transverse_inertia_scale)
