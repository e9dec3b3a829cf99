"""Wire a scene through the three rooms: mesh -> fem_loads -> dynamics.

World frame: ``X`` horizontal in the paper's vertical plane, ``Y`` horizontal
out of it, ``Z`` up; the target fills ``Z < 0``.  Body frame: ``x`` along the
projectile axis towards the nose, origin at the centre of mass; at the start
``y`` is the world ``Y`` (for zero yaw), so a pitch rate in the vertical plane
is ``angular_velocity[1]``.  Angles in the vertical plane are measured from the
inward normal ``-Z`` towards ``+X``: the oblique angle ``beta`` of the
velocity, the axis angle ``phi = beta + alpha`` and the attack angle
``alpha``.
"""

from __future__ import annotations

import functools
import hashlib
import importlib.metadata
import json
import math
import os
import tempfile
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from threadpoolctl import threadpool_limits

from dynamics import METHODS, Event, RigidBody, SpeedBelow, State, Trajectory, simulate
from dynamics.quaternion import multiply, rotation_matrix
from fem_loads import (DAFLLoads, MassProperties, ResistanceLaw, SurfaceQuadrature, mass_properties,
                       resistance_law, surface_quadrature, to_skfem)
from fem_loads.resistance import locking_cavity_expansion
from fem_loads.target import FreeSurface, Friction, LayeredTarget
from mesh import (BODY, COUNTERWEIGHT, ConeNose, Interior, OgiveNose, Profile, ProjectileGeometry,
                  cached_mesh, place_counterweight)
from mesh.io import MESH_FORMAT_VERSION, cache_dir
from mesh.profile import BluntOgiveNose, SecantOgiveNose

from .schema import LawSpec, MaterialLawSpec, Numerics, Projectile, Scene

__all__ = ["PreparedProjectile", "prepare_projectile", "preparation_key", "resolve_law", "initial_state", "run_scene",
           "scene_loads", "projectile_geometry",
           "RunResult", "STOPPED", "EXITED", "DEFAULT_BODY_DENSITY"]

STOPPED, EXITED = "stopped", "exited"
DEFAULT_BODY_DENSITY = 7850.0  # steel (kg/m^3)


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


def nose_of(spec) -> OgiveNose | ConeNose | SecantOgiveNose | BluntOgiveNose:
    """The mesh-room nose of a scene's nose table."""
    match spec.shape:
        case "ogive":
            return OgiveNose(spec.crh)
        case "cone":
            return ConeNose(spec.half_angle)
        case "secant_ogive":
            return SecantOgiveNose(spec.crh, spec.length)
        case "hemisphere":
            return OgiveNose(0.5)
        case "blunt":
            return BluntOgiveNose(spec.crh, spec.flat_radius)
    raise ValueError(f"nose.shape = {spec.shape!r}: unknown")


def projectile_geometry(spec: Projectile) -> tuple[ProjectileGeometry, dict[int, float]]:
    """The geometry and region densities a projectile spec describes (before any mass scaling)."""
    profile = Profile(spec.diameter, spec.length, nose_of(spec.nose))
    body_density = spec.body_density or DEFAULT_BODY_DENSITY
    if spec.interior is None:
        return ProjectileGeometry(profile), {BODY: body_density}
    interior = Interior(spec.interior.wall_thickness, spec.interior.tail_thickness)
    weight = spec.counterweight
    if weight is None:
        return ProjectileGeometry(profile, interior), {BODY: body_density}
    if weight.start is not None:
        span = (weight.start, weight.end)
    else:
        span = place_counterweight(profile, interior, body_density, weight.density, spec.mass,
                                   spec.centre_target)
    return ProjectileGeometry(profile, interior, span), {BODY: body_density, COUNTERWEIGHT: weight.density}


# bump when the mass properties or the surface quadrature computed from a mesh change
PREPARED_FORMAT_VERSION = 3  # 3: mirror-symmetric quadrature (with its quarters) and mass properties


def _prepared_path(spec_json: str, numerics_json: str) -> Path:
    """Cache file of a projectile's mass properties and quadrature (beside the meshes)."""
    record = {"projectile": spec_json, "numerics": numerics_json, "format": PREPARED_FORMAT_VERSION,
              "mesh_format": MESH_FORMAT_VERSION, "gmsh": importlib.metadata.version("gmsh"),
              "scikit-fem": importlib.metadata.version("scikit-fem")}
    key = hashlib.sha256(json.dumps(record, sort_keys=True).encode()).hexdigest()[:24]
    return cache_dir() / f"prepared-{key}.npz"


def _load_prepared(path: Path, geometry: ProjectileGeometry) -> PreparedProjectile | None:
    try:
        with np.load(path) as data:
            mass = MassProperties(float(data["mass"]), data["centre"], data["inertia"], float(data["volume"]))
            quarters = data["mirror_quarters"]
            quadrature = SurfaceQuadrature(data["points"], data["normals"], data["weights"],
                                           quarters if quarters.size else None)
            return PreparedProjectile(geometry, mass, quadrature, int(data["n_tetra"]))
    except (OSError, KeyError, ValueError, EOFError, zipfile.BadZipFile):
        path.unlink(missing_ok=True)  # absent, or a corrupt entry: compute again
        return None


def _save_prepared(path: Path, prepared: PreparedProjectile) -> None:
    """Write atomically: a concurrent reader sees the whole file or none."""
    path.parent.mkdir(parents=True, exist_ok=True)
    m, q = prepared.mass, prepared.quadrature
    with tempfile.NamedTemporaryFile(dir=path.parent, suffix=".npz.tmp", delete=False) as tmp:
        np.savez(tmp, mass=m.mass, centre=m.centre, inertia=m.inertia, volume=m.volume, points=q.points,
                 normals=q.normals, weights=q.weights, n_tetra=prepared.n_tetra,
                 mirror_quarters=q.mirror_quarters if q.mirror_quarters is not None else np.empty(0, dtype=np.int64))
    os.replace(tmp.name, path)


@functools.lru_cache(maxsize=16)
def _prepare(spec_json: str, numerics_json: str) -> PreparedProjectile:
    spec = Projectile.model_validate_json(spec_json)
    numerics = Numerics.model_validate_json(numerics_json)
    geometry, densities = projectile_geometry(spec)
    path = _prepared_path(spec_json, numerics_json)
    if path.exists() and (prepared := _load_prepared(path, geometry)) is not None:
        return prepared
    prepared = _compute_prepared(spec, numerics, geometry, densities)
    _save_prepared(path, prepared)
    return prepared


def _compute_prepared(spec: Projectile, numerics: Numerics, geometry: ProjectileGeometry,
                      densities: dict[int, float]) -> PreparedProjectile:
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
        if spec.mass_properties is not None:
            given = spec.mass_properties
            mass = MassProperties.axisymmetric(given.mass, given.centre_of_mass, given.axial_inertia,
                                               given.transverse_inertia)
        else:
            mass = mass_properties(mesh, densities, fem_mesh)
            if spec.mass is not None and spec.counterweight is None:
                # a homogeneous body of the given mass: scale its density
                scale = spec.mass / mass.mass
                mass = MassProperties(spec.mass, mass.centre, mass.inertia * scale, mass.volume)
        quadrature = surface_quadrature(mesh, mass.centre, geometry.profile, numerics.normals,
                                        numerics.quadrature_order, fem_mesh)
    except Exception as exc:  # scikit-fem: "Newton iteration didn't converge" on distorted curved elements
        raise RuntimeError(f"{size}: the elements of this mesh are too distorted to integrate ({exc});"
                           " a finer numerics.mesh_size, or numerics.geometry_order = 1, usually works") from exc
    if spec.transverse_inertia_scale != 1.0:
        axial, transverse = mass.axial_inertia, mass.transverse_inertia
        lowest = 0.5 * axial / transverse  # I_axial <= 2 I_transverse for every rigid body
        if spec.transverse_inertia_scale < lowest:
            raise ValueError(f"projectile.transverse_inertia_scale = {spec.transverse_inertia_scale:g}: the transverse"
                             f" moments ({spec.transverse_inertia_scale * transverse:.3g} kg m^2) would be less than"
                             f" half the axial moment ({axial:.3g} kg m^2), which no rigid body has (allowed for this"
                             f" projectile: transverse_inertia_scale >= {lowest:.3g})")
        mass = mass.with_transverse_scale(spec.transverse_inertia_scale)
    return PreparedProjectile(geometry, mass, quadrature, len(mesh.tetra))


def prepare_projectile(scene: Scene) -> PreparedProjectile:
    """Mesh, mass properties and surface quadrature of a scene's projectile.

    Computed once per process (memory) and once per machine: the mesh and the
    prepared arrays are kept in the disk cache (``$PENETRATE_CACHE_DIR``), so
    a later run of the same projectile and numerics reads them back without
    meshing, assembling or importing gmsh and scikit-fem.
    """
    return _prepare(*preparation_key(scene))


def preparation_key(scene: Scene) -> tuple[str, str]:
    """What a prepared projectile depends on: the projectile and the mesh and quadrature numerics (JSON)."""
    return (scene.projectile.model_dump_json(),
            scene.numerics.model_dump_json(include={"mesh_size", "geometry_order", "normals", "quadrature_order"}))


def resolve_law(law: str | LawSpec | MaterialLawSpec) -> ResistanceLaw:
    """The resistance law a scene names, gives by coefficients or derives from material constants."""
    if isinstance(law, str):
        return resistance_law(law)
    if isinstance(law, MaterialLawSpec):
        return locking_cavity_expansion(law.sigma_0, law.rho_0, law.locking_strain)
    return ResistanceLaw.from_coefficients(law.A, law.sigma_0, law.B, law.rho_0)


def initial_attitude(oblique_angle: float, attack_angle: float, yaw_angle: float) -> np.ndarray:
    """Body-to-world attitude quaternion at impact (angles in degrees).

    The axis leaves the downward vertical by ``oblique_angle + attack_angle`` in the
    ``XZ`` plane and turns by ``yaw_angle`` towards ``Y``; the body ``y`` axis stays in
    the plane of the axis and ``Y``.  Built as the exact nose-down quarter turn about
    ``Y``, ``(sqrt(1/2), 0, sqrt(1/2), 0)``, times the pitch and yaw turns, so that a
    straight normal impact starts exactly on the axis (``cos`` and ``sin`` of 45 degrees
    differ by one ulp in floating point).
    """
    pitch = math.radians(oblique_angle + attack_angle) / 2  # about -Y
    yaw = math.radians(yaw_angle) / 2  # about body z
    half = math.sqrt(0.5)
    nose_down = np.array([half, 0.0, half, 0.0])
    return multiply(multiply(nose_down, np.array([math.cos(pitch), 0.0, -math.sin(pitch), 0.0])),
                    np.array([math.cos(yaw), 0.0, 0.0, math.sin(yaw)]))


def initial_state(scene: Scene, prepared: PreparedProjectile) -> State:
    """The tip touches the surface at the origin; at grazing incidence the lowest point does."""
    impact = scene.impact
    attitude = initial_attitude(impact.oblique_angle, impact.attack_angle, impact.yaw_angle)
    rotation = rotation_matrix(attitude)
    beta = math.radians(impact.oblique_angle)
    velocity = impact.speed * np.array([math.sin(beta), 0.0, -math.cos(beta)])
    position = rotation @ (-prepared.tip)  # the tip at the origin
    # lowest point of the exact surface relative to the tip: min over s of
    # (-s axis_Z - r(s) |transverse part of Z|)
    profile = prepared.profile
    s = np.linspace(0.0, profile.length, 20001)
    up = rotation[2]
    lowest = float(np.min(-s * up[0] - profile.radius_at(s) * math.hypot(up[1], up[2])))
    position[2] -= min(lowest, 0.0)
    return State(0.0, position, velocity, attitude,
                 np.asarray(impact.angular_velocity, dtype=float))


@dataclass
class RunResult:
    """A finished run: the scene, its projectile, the trajectory and the wall time."""

    scene: Scene
    prepared: PreparedProjectile
    trajectory: Trajectory
    wall_time: float
    integration_time: float


def scene_loads(scene: Scene, prepared: PreparedProjectile) -> DAFLLoads:
    """The DAFL load function of a scene, with exactly the effects the scene asks for."""
    target = scene.target
    if target.layers is None:
        law = resolve_law(target.law)
    else:
        law = LayeredTarget(tuple(layer.thickness for layer in target.layers[:-1]),
                            tuple(resolve_law(layer.law) for layer in target.layers))
    effects = scene.effects
    friction = None
    if effects.friction.model != "none":
        friction = Friction(effects.friction.coefficient, effects.friction.cap)
    free_surface = None
    if effects.free_surface is not None:
        free_surface = FreeSurface(effects.free_surface.depth, effects.free_surface.surface_fraction)
    return DAFLLoads(prepared.quadrature, law, scene.numerics.normal_velocity_guard, friction=friction,
                     separation=effects.separation, free_surface=free_surface)


class WithGravity:
    """A load function plus the weight ``-m g e_Z`` of the body (world frame)."""

    def __init__(self, loads, mass: float, acceleration: float) -> None:
        self.loads = loads
        self.weight = np.array([0.0, 0.0, -mass * acceleration])

    def __call__(self, position, velocity, rotation, angular_velocity):
        force, moment = self.loads(position, velocity, rotation, angular_velocity)
        return force + self.weight, moment


def run_scene(scene: Scene, initial: State | None = None) -> RunResult:
    """Run one scene end to end.

    Parameters
    ----------
    scene : Scene
        The validated scene.
    initial : State, optional
        Start from this state instead of the scene's impact conditions.
    """
    start = time.perf_counter()
    prepared = prepare_projectile(scene)
    numerics = scene.numerics
    loads = scene_loads(scene, prepared)
    body = RigidBody(prepared.mass.mass, prepared.mass.inertia)
    effects = scene.effects
    driving = WithGravity(loads, body.mass, effects.gravity_acceleration) if effects.gravity else loads
    # the energy guard needs loads that only dissipate: gravity and no-separation can do work
    dissipative = numerics.energy_guard and effects.separation and not effects.gravity
    state = initial_state(scene, prepared) if initial is None else initial
    events = [
        SpeedBelow(STOPPED, numerics.stop_speed),
        # every surface point back above the surface after having been inside
        Event(EXITED, lambda st: loads.lowest_height(st.position, st.rotation), direction=1),
    ]
    method = METHODS[numerics.integrator]()
    integrate_start = time.perf_counter()
    # one BLAS thread: the products over ~1e4 points gain nothing from threads, and threads that
    # wait for a busy core (a sweep runs one process per core) cost up to 50x; one thread also
    # fixes the summation order, so results do not depend on the machine's core count
    with threadpool_limits(limits=1, user_api="blas"):
        trajectory = _integrate(scene, prepared, body, driving, state, method, events, dissipative)
    end = time.perf_counter()
    return RunResult(scene, prepared, trajectory, end - start, end - integrate_start)


# attitude errors are measured against this angle (rad), not against a radian: the disturbances
# of interest are of the order of a degree (docs/numerics.md, Hard cases)
ANGLE_SCALE = 1e-2
# the step floor below the time step: 10 halvings of the energy guard (docs/numerics.md, Hard cases)
FLOOR_FRACTION = 2.0 ** -10


def _integrate(scene: Scene, prepared: PreparedProjectile, body: RigidBody, driving, state: State, method,
               events: list[Event], dissipative: bool) -> Trajectory:
    """Integrate one run with the scene's integrator.

    ``rk4`` steps by ``numerics.time_step``.  ``dopri54`` controls the error
    with ``numerics.rtol`` and absolute tolerances ``rtol`` times the
    projectile length (position, path), the impact speed (velocity),
    :data:`ANGLE_SCALE` (rotation) and ``ANGLE_SCALE`` times the impact speed
    over the length (angular velocity); it starts with a step of 1e-3 of the
    length over the speed and never shortens a step below
    ``numerics.time_step``: a step of that size that fails the tolerance is
    accepted (``forced_steps``), since across the shank's ``Vn = 0`` switch no
    step meets a smooth error model.  Either integrator ends the run with
    ``step_floor`` when it would need a step below ``time_step / 1024`` (the
    energy guard, a non-finite trial step of ``dopri54``).
    """
    numerics = scene.numerics
    floor = numerics.time_step * FLOOR_FRACTION
    if method.adaptive:
        length, speed = prepared.profile.length, scene.impact.speed
        rate = ANGLE_SCALE * speed / length
        scales = np.array([length] * 3 + [speed] * 3 + [ANGLE_SCALE] * 3 + [rate] * 3 + [length])
        trajectory = simulate(body, driving, state, method, time_limit=numerics.time_limit,
                              rtol=numerics.rtol, atol=numerics.rtol * scales,
                              first_step=1e-3 * length / speed,
                              forced_step=numerics.time_step, min_step=floor, events=events,
                              dissipative=dissipative)
    else:
        trajectory = simulate(body, driving, state, method, time_limit=numerics.time_limit,
                              time_step=numerics.time_step, min_step=floor, events=events,
                              dissipative=dissipative)
    return trajectory
