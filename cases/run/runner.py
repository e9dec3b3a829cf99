"""Run one scene: the start state, the load function, the integrator and its step control.

World frame: ``X`` horizontal in the paper's vertical plane, ``Y`` horizontal
out of it, ``Z`` up; the target lies below its front face, the plane ``Z = 0``
turned about ``Y`` by ``target.inclination``.  Body frame: ``x`` along the
projectile axis towards the nose, origin at the centre of mass; at the start
``y`` is the world ``Y`` (for zero yaw), so a pitch rate in the vertical plane
is ``angular_velocity[1]``.  Angles in the vertical plane are measured from the
inward normal ``-Z`` towards ``+X``: the oblique angle ``beta`` of the
velocity, the axis angle ``phi = beta + alpha`` and the attack angle
``alpha``.
"""

from __future__ import annotations

import functools
import math
import sys
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

import numpy as np
from threadpoolctl import ThreadpoolController

from dynamics import (
    METHODS,
    STEP_FLOOR,
    AdvanceEnds,
    EnergyGuard,
    ErrorControl,
    Event,
    FixedStep,
    LoadFunction,
    RigidBody,
    SpeedBelow,
    State,
    StepControl,
    Trajectory,
    simulate,
)
from dynamics.integrators import Stepper
from dynamics.quaternion import hamilton_scalars, rotation_matrices, rotation_matrix
from fem_loads.target import FrontFace, face_height_scalars

from ..scene import Scene
from .prepare import PreparedProjectile, prepare_projectile

if TYPE_CHECKING:
    from dynamics import RungeKutta
    from dynamics.compiled_rk import CompiledLoad, CompiledRungeKutta
    from fem_loads import DAFLLoads
    from mesh import Profile

__all__ = [
    "RunResult",
    "run_scene",
    "compiled_driving",
    "initial_state",
    "initial_attitude",
    "impact_positions",
    "step_control",
    "tip_depths",
    "WithGravity",
    "STOPPED",
    "stop_events",
    "EXITED",
    "PERFORATED",
    "RICOCHETED",
    "ANGLE_SCALE",
    "FLOOR_FRACTION",
    "COARSE_CHECK_STEPS",
    "COARSE_ERROR",
    "COARSE_TURN",
]

#: ``lowest_height(position, attitude, face=None)`` (m): the lowest point of the loaded band above the front face,
#: or above ``face``
LowestHeight = Callable[..., float]
STOPPED, EXITED = "stopped", "exited"
# the whole body has left the target's rear face; has left its front face without ever having been wholly inside
PERFORATED, RICOCHETED = "perforated", "ricocheted"
# a run whose steps fail at the floor has stopped when it has at most this share of its path left to travel to rest
# under its load (runner._at_rest): well below a run's discretisation error (0.05 % of the depth at the mesh sizes
# docs/accuracy.md recommends)
REST_TRAVEL = 1e-4
# attitude errors are measured against this angle (rad), not against a radian: the disturbances
# of interest are of the order of a degree (docs/evidence-numerics.md)
ANGLE_SCALE = 1e-2
# the step floor below the time step: 10 halvings of the energy guard (docs/evidence-numerics.md)
FLOOR_FRACTION = 2.0**-10
# the longest step across a face inside the target, in nose lengths (FaceCrossings)
FACE_TRAVEL = 0.25
# a fixed-step run of fewer steps is integrated again at half its step, and the difference judged
# (summary.run_warnings): below it the step may not resolve the run, above it the check would cost
COARSE_CHECK_STEPS = 1000
# a fixed-step run whose depth or path length (relative) or final axis direction (deg) moves by more than these
# at half its step is warned of
COARSE_ERROR = 0.01
COARSE_TURN = 0.5
# a share of steps above which retaken or forced steps mean the numerics do not suit the scene
WARN_SHARE = 0.1


@dataclass
class RunResult:
    """A finished run: the scene, its projectile, the trajectory and the wall time (s)."""

    scene: Scene
    prepared: PreparedProjectile
    trajectory: Trajectory
    wall_time: float
    integration_time: float


def initial_attitude(
    oblique_angle: float | np.ndarray, attack_angle: float | np.ndarray, yaw_angle: float | np.ndarray
) -> np.ndarray:
    """Body-to-world attitude quaternion at impact (angles in degrees), shape ``(4,)``; for arrays of angles
    (broadcast together) one quaternion per entry, shape ``(..., 4)``.

    The axis leaves the downward vertical by ``oblique_angle + attack_angle`` in the
    ``XZ`` plane and turns by ``yaw_angle`` towards ``Y``; the body ``y`` axis stays in
    the plane of the axis and ``Y``.  Built as the exact nose-down quarter turn about
    ``Y``, ``(sqrt(1/2), 0, sqrt(1/2), 0)``, times the pitch and yaw turns, so that a
    straight normal impact starts exactly on the axis (``cos`` and ``sin`` of 45 degrees
    differ by one ulp in floating point).
    """
    # floats or arrays (the quaternion arithmetic is elementwise)
    pitch: Any = np.radians(np.add(oblique_angle, attack_angle)) / 2  # about -Y
    yaw: Any = np.radians(yaw_angle) / 2  # about body z
    half = math.sqrt(0.5)
    pitched = hamilton_scalars(half, 0.0, half, 0.0, np.cos(pitch), 0.0, -np.sin(pitch), 0.0)
    turned = hamilton_scalars(*pitched, np.cos(yaw), 0.0, 0.0, np.sin(yaw))
    return np.stack(np.broadcast_arrays(*turned), axis=-1).astype(float)


def initial_state(scene: Scene, prepared: PreparedProjectile) -> State:
    """The tip touches the front face at the origin; at grazing incidence the lowest point does."""
    impact = scene.impact
    attitude = initial_attitude(impact.oblique_angle, impact.attack_angle, impact.yaw_angle)
    rotation = rotation_matrix(attitude)
    beta = math.radians(impact.oblique_angle)
    velocity = impact.speed * np.array([math.sin(beta), 0.0, -math.cos(beta)])
    position = impact_positions(prepared, rotation[None], scene.target.face.normal)[0]
    return State(0.0, position, velocity, attitude, np.asarray(impact.angular_velocity, dtype=float))


def impact_positions(
    prepared: PreparedProjectile, rotations: np.ndarray, normal: tuple[float, float, float] = (0.0, 0.0, 1.0)
) -> np.ndarray:
    """The centre of mass at impact for each attitude ``rotations`` (shape ``(n, 3, 3)``, body to world),
    shape ``(n, 3)``, m: the tip at the origin, lifted along the front face's ``normal`` (world frame) until no
    point of the body lies below the face (through the origin)."""
    positions = -rotations @ prepared.tip  # the tip at the origin
    ups = np.asarray(normal) @ rotations  # R^T n: the face's normal in each body frame
    if prepared.outline is None:
        lowest = profile_lowest(prepared.profile, ups[:, 0], np.hypot(ups[:, 1], ups[:, 2]))
    else:  # a file's body: its lowest quadrature point (on the exact surface, within a fraction of an element)
        lowest = np.min((prepared.quadrature.points - prepared.tip) @ ups.T, axis=0)
    positions -= np.minimum(lowest, 0.0)[:, None] * np.asarray(normal)
    return positions


#: the points of a profile that :func:`profile_lowest` takes, evenly spaced along the axis
PROFILE_POINTS = 20001


@functools.lru_cache(maxsize=8)
def _upper_hull(profile: Profile) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The upper convex hull of the profile's points ``(s, r(s))`` (:data:`PROFILE_POINTS` of them): its
    vertices' ``s`` and ``r`` (m, by ``s``) and the negated slopes of its edges, which rise along it.

    Points under the chord of their neighbours are dropped, all at once, until none is left: each dropped
    point lies under the hull, so dropping them together is safe, and a profile needs a few passes."""
    s = np.linspace(0.0, profile.length, PROFILE_POINTS)
    r = profile.radius_at(s)
    keep = np.ones(len(s), dtype=bool)
    while True:
        si, ri = s[keep], r[keep]
        above = (ri[1:-1] - ri[:-2]) * (si[2:] - si[:-2]) - (ri[2:] - ri[:-2]) * (si[1:-1] - si[:-2]) > 0.0
        if above.all():
            return si, ri, -np.diff(ri) / np.diff(si)
        kept = np.flatnonzero(keep)
        keep[kept[1:-1][~above]] = False


def profile_lowest(profile: Profile, along: np.ndarray, across: np.ndarray) -> np.ndarray:
    """The lowest height of the body surface relative to its tip, along an upward direction with body
    components ``along`` the axis and ``across`` it (``>= 0``, the transverse part's length), one per entry:
    the minimum over the profile's points of ``-s along - r(s) across`` (m).

    Evaluated on the upper convex hull of the points (:func:`_upper_hull`), where a linear function's
    extreme lies: the vertex where the edges' slopes pass ``-along / across`` and its two neighbours, so
    any number of directions costs a search each, not a sweep over the points."""
    s, r, falling = _upper_hull(profile)
    with np.errstate(divide="ignore", invalid="ignore"):
        ratio = np.divide(along, across)
    vertex = np.searchsorted(falling, ratio)
    candidates = np.clip(vertex[:, None] + np.arange(-1, 2), 0, len(s) - 1)
    return np.min(-(along[:, None] * s[candidates]) - across[:, None] * r[candidates], axis=1)


class WithGravity:
    """A load function plus the weight ``-m g e_Z`` of the body (world frame)."""

    def __init__(self, loads: LoadFunction, mass: float, acceleration: float) -> None:
        self.loads = loads
        self.weight = np.array([0.0, 0.0, -mass * acceleration])

    def __call__(
        self, position: np.ndarray, velocity: np.ndarray, rotation: np.ndarray, angular_velocity: np.ndarray
    ) -> tuple[np.ndarray, np.ndarray]:
        force, moment = self.loads(position, velocity, rotation, angular_velocity)
        return force + self.weight, moment


def step_control(scene: Scene, length: float) -> StepControl:
    """The step control of the scene's integrator (``length``: the projectile's, m).

    ``rk4`` steps by ``numerics.time_step``.  ``dopri54`` controls the error
    with ``numerics.rtol`` and absolute tolerances ``rtol`` times the
    projectile length (position, path), the impact speed (velocity),
    :data:`ANGLE_SCALE` (rotation) and ``ANGLE_SCALE`` times the impact speed
    over the length (angular velocity) and starts with a step of 1e-3 of the
    length over the speed.  When the load has a sharp switch (both contact
    widths or ``entry_smoothing`` zero) it never shortens a step below
    ``numerics.time_step``: a step of that size that fails the tolerance is
    accepted (``forced_steps``), since across a jump of the load no step meets
    a smooth error model; with the continuous load (the default) no step is
    forced.  Either ends the run with ``step_floor`` when it would need a step
    below ``time_step / 1024`` (:data:`FLOOR_FRACTION`).
    """
    numerics = scene.numerics
    floor = numerics.time_step * FLOOR_FRACTION
    if not METHODS[numerics.integrator]().adaptive:
        return FixedStep(numerics.time_step, min_step=floor)
    speed = scene.impact.speed
    rate = ANGLE_SCALE * speed / length
    scales = np.array([length] * 3 + [speed] * 3 + [ANGLE_SCALE] * 3 + [rate] * 3 + [length])
    sharp = scene.effects.sharp_contact or numerics.entry_smoothing == 0.0
    return ErrorControl(
        numerics.rtol,
        numerics.rtol * scales,
        first_step=1e-3 * length / speed,
        forced_step=numerics.time_step if sharp else 0.0,
        min_step=floor,
    )


def compiled_driving(
    scene: Scene, loads: DAFLLoads, body: RigidBody, method: RungeKutta
) -> tuple[CompiledLoad, CompiledRungeKutta, LowestHeight]:
    """The compiled load (with the body's weight when the scene has gravity), step and exit height of a
    scene's ``loads`` (:func:`cases.run.compiled.compiled_step`): what a compiled run drives its
    integration with, and what warming the caches compiles."""
    from .compiled import compiled_step

    effects = scene.effects
    weight = np.array([0.0, 0.0, -body.mass * effects.gravity_acceleration]) if effects.gravity else None
    return compiled_step(loads, method, body, weight)


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
    scene = scene.with_kernel(many_runs=False)
    prepared = prepare_projectile(scene)
    numerics, effects = scene.numerics, scene.effects
    loads = scene.loads(prepared.quadrature)
    body = RigidBody(prepared.mass.mass, prepared.mass.inertia)
    method: Stepper = METHODS[numerics.integrator]()

    def numpy_lowest_height(position: np.ndarray, attitude: np.ndarray, face: FrontFace | None = None) -> float:
        return loads.lowest_height(position, rotation_matrix(attitude), face)

    # the numpy path's, or the compiled step's
    lowest_height: LowestHeight = numpy_lowest_height
    driving: LoadFunction
    if numerics.kernel == "compiled":
        driving, method, lowest_height = compiled_driving(scene, loads, body, METHODS[numerics.integrator]())
    else:
        driving = WithGravity(loads, body.mass, effects.gravity_acceleration) if effects.gravity else loads
    control = step_control(scene, prepared.length)
    # the energy guard (in integrate) needs loads that only dissipate: gravity and no-separation can do work
    state = initial_state(scene, prepared) if initial is None else initial
    events = [
        *stop_events(scene),
        # every surface point back above the surface after having been inside
        Event(EXITED, lambda st: lowest_height(st.position, st.attitude), direction=1),
    ]
    rear = scene.target.build_rear_face()
    if rear is not None:  # every surface point past the rear face
        events.append(Event(PERFORATED, lambda st: lowest_height(st.position, st.attitude, rear), direction=1))
    inner_faces = scene.target.inner_faces
    if inner_faces and isinstance(control, ErrorControl):
        travel = FACE_TRAVEL * prepared.nose_length
        events.append(FaceCrossings(loads.front_face, inner_faces, loads.reach, travel))
    integrate_start = time.perf_counter()
    # one BLAS thread: the products over ~1e4 points gain nothing from threads, and threads that
    # wait for a busy core (a sweep runs one process per core) cost up to 50x; one thread also
    # fixes the summation order, so results do not depend on the machine's core count
    with _blas("scipy.linalg" in sys.modules).limit(limits=1, user_api="blas"):

        def integrate(control: StepControl) -> Trajectory:
            # the energy guard counts its retakes: each integration its own
            guard = EnergyGuard(control.min_step) if guarded else None
            return simulate(
                body, driving, state, method, control, time_limit=numerics.time_limit, events=events, guard=guard
            )

        guarded = numerics.energy_guard and effects.separation and not effects.gravity
        trajectory = integrate(control)
        if isinstance(control, FixedStep) and trajectory.statistics["steps"] < COARSE_CHECK_STEPS:
            error, turn = _time_error(trajectory, control, integrate, lambda run: _depth(run, prepared, scene))
            trajectory.statistics.update(coarse_step_error=error, coarse_step_turn=turn)
    if trajectory.end_reason == EXITED and not _went_in(trajectory, lowest_height, loads.front_face.behind(0.0)):
        trajectory.end_reason = RICOCHETED
    if trajectory.end_reason == STEP_FLOOR and _at_rest(trajectory, body.mass, scene):
        trajectory.end_reason = STOPPED
        trajectory.statistics["stopped_at_step_floor"] = True
    end = time.perf_counter()
    return RunResult(scene, prepared, trajectory, end - start, end - integrate_start)


def stop_events(scene: Scene) -> list[Event]:
    """The two ends of a run that stops inside the target: its speed falls below :attr:`Scene.stop_speed`, or the
    body, slower than ``numerics.slow_fraction`` of the impact speed, stops moving nose first (docs/numerics.md)."""
    return [
        SpeedBelow(STOPPED, scene.stop_speed),
        AdvanceEnds(STOPPED, scene.numerics.slow_fraction * scene.impact.speed),
    ]


class FaceCrossings(Event):
    """Not an end, a step limit: a step carries the body at most ``travel`` (m) past the point where its bounding
    sphere, widened by the entry band (radius ``reach``, m), first touches one of the target's inner faces (its
    interfaces and its rear face, at ``depths`` m below the front face ``face``), and at most ``travel`` while it
    overlaps one.  Why: across a face the load changes over the nose's length, and a Dormand-Prince step that
    jumps over the change is misjudged by its own error estimate (test 2 through a 2 m slab: 10 steps, the
    residual speed 0.27 % high; docs/evidence-targets.md)."""

    # set in __init__ (not dataclass fields: the class is not a dataclass of its own)
    face: FrontFace
    depths: tuple[float, ...]
    reach: float
    travel: float

    def __init__(self, face: FrontFace, depths: tuple[float, ...], reach: float, travel: float) -> None:
        super().__init__("face_crossings", lambda state: 1.0)  # never crosses zero
        for name, value in (("face", face), ("depths", depths), ("reach", reach), ("travel", travel)):
            object.__setattr__(self, name, value)

    def fired(self, before: State, after: State, g_before: float, g_after: float) -> bool:
        return False

    def step_limit(self, state: State, evaluation: object) -> float:
        # the fastest point's speed bounds how far any part of the body moves
        speed = state.speed + float(np.linalg.norm(state.angular_velocity)) * self.reach
        if not speed > 0.0:
            return math.inf
        depth = -face_height_scalars(state.position, self.face.normal, self.face.offset)
        return min(max(abs(depth - face) - self.reach, 0.0) + self.travel for face in self.depths) / speed


def _at_rest(trajectory: Trajectory, mass: float, scene: Scene) -> bool:
    """Whether a run whose steps failed at the floor had as good as stopped: the body slow (at most
    ``numerics.slow_fraction`` of the impact speed) and braked, with a travel left to rest under its last load,
    ``v^2 / (2 a)``, of at most :data:`REST_TRAVEL` of its path.  Why: near rest the contact ramp narrows with the
    speed, so the load of an aligned shank's sliding contact stiffens without bound and chatters faster than any
    step the error control accepts (the 155 mm shell with its nose through the rear face of a 1.2 m slab at
    725-740 m/s: 4-22 um left to travel at 0.9-1.9 m/s); the depth is then within that travel (docs/numerics.md,
    the end of a run)."""
    velocity = trajectory.velocity[-1]
    speed = float(np.linalg.norm(velocity))
    if not 0.0 < speed <= scene.numerics.slow_fraction * scene.impact.speed:
        return False
    deceleration = -float(trajectory.force[-1] @ velocity) / (mass * speed)
    return deceleration > 0.0 and speed**2 / (2 * deceleration) <= REST_TRAVEL * float(trajectory.path_length[-1])


def _went_in(trajectory: Trajectory, lowest_height: LowestHeight, inside: FrontFace) -> bool:
    """Whether the whole body was inside the target (beyond its entry band) at some step: ``inside`` is the front
    face turned to face back out (:meth:`FrontFace.behind`), above which a point lies by its depth."""
    return any(lowest_height(p, q, inside) > 0.0 for p, q in zip(trajectory.position, trajectory.attitude))


def _time_error(
    run: Trajectory,
    control: FixedStep,
    integrate: Callable[[StepControl], Trajectory],
    depth: Callable[[Trajectory], float],
) -> tuple[float, float]:
    """An estimate of a fixed-step run's time error: how far the depth and the path length (relative, the
    larger of the two; inf when the run ends otherwise) and the final direction of the axis (deg) move when
    the run is integrated again at half its step (twice as dear).  ``depth`` gives a trajectory's largest
    depth of the nose tip (m).

    The run's own error is about that move where the method keeps its fourth order, and up to twice it where
    the contact's switch leaves it first order.  Not the cheaper run at twice the step: where the error has
    not yet begun to fall with the step, the two can err alike and agree (the finned test 2 body into 20 MPa
    concrete at 299 m/s: 4.3 % and 4.8 % deep at 2e-4 and 1e-4 s, 0.5 % apart; 2.9 % at 5e-5 s).  The depth
    counts as well as the path: an oblique shot that glances off can keep its path to a per cent and miss
    its depth by more (a 30 mm rod at 100 m/s and 42 deg into 1 GPa: path 1.5 %, depth 2.5 % short in 17
    steps)."""
    return _moved(run, integrate(FixedStep(control.time_step / 2, min_step=control.min_step)), depth)


def _moved(run: Trajectory, other: Trajectory, depth: Callable[[Trajectory], float]) -> tuple[float, float]:
    """How far ``other`` ends from ``run``: the larger relative move of the path length and the depth, and the
    axis direction (deg)."""
    if other.end_reason != run.end_reason:
        return math.inf, math.inf
    moves = [0.0]
    for measure in (lambda tr: float(tr.path_length[-1]), depth):
        own = measure(run)
        if own > 0:
            moves.append(abs(measure(other) - own) / own)
    axes = [rotation_matrix(tr.attitude[-1])[:, 0] for tr in (run, other)]
    turn = math.degrees(math.acos(min(1.0, max(-1.0, float(axes[0] @ axes[1])))))
    return max(moves), turn


def tip_depths(position: np.ndarray, rotation: np.ndarray, tip: np.ndarray, face: FrontFace) -> np.ndarray:
    """The nose tip's depth (m) below ``face`` at each state: the centre's ``position``, shape (n, 3), the body's
    ``rotation`` matrices, shape (n, 3, 3), and the ``tip`` from the centre of mass in the body frame (m)."""
    return -face_height_scalars((position + rotation @ tip).T, face.normal, face.offset)


def _depth(run: Trajectory, prepared: PreparedProjectile, scene: Scene) -> float:
    """A trajectory's largest depth of the nose tip below the front face (m): the summary's ``depth``."""
    return float(np.max(tip_depths(run.position, rotation_matrices(run.attitude), prepared.tip, scene.target.face)))


@functools.cache
def _blas(scipy_linalg: bool) -> ThreadpoolController:
    """The loaded BLAS libraries, found once per process (a search reads every loaded library's header:
    16 ms, a tenth of a run of #3; a forked worker inherits the result) and again once scipy.linalg has
    loaded its own BLAS (``scipy_linalg``)."""
    return ThreadpoolController()
