"""``penetrate predict``: the characteristic speeds from a reduced pitch-plane model, without a full trajectory.

The model (docs/theory.md derives it and says what it neglects):

* **Loads.**  The scene's DAFL (its law, contact and entry ramps, friction) integrated over the
  exact surface of revolution ring by ring (:mod:`fem_loads.kernels.rings`): in pitch-plane motion the
  normal velocity and the height are linear in ``cos phi`` around each ring, so the stress is
  integrated between the law's switches in closed form, without a mesh or its quadrature points.
* **Motion.**  Three degrees of freedom in the vertical plane (:mod:`dynamics.pitch_plane`), the
  mass and transverse moment of inertia of the scene's projectile.
* **The characteristic speeds** then follow from the same definitions as the measured ones
  (:mod:`..speeds.characteristic`): the convergent velocity from a reduced run at the scene's impact speed (raised
  by 15 % while that run is stable, as ``penetrate convergent`` does), the critical impact velocity
  by the full runs' threshold search over reduced runs, one a round, to the same 5 m/s.

A reduced run costs about a millisecond where a run of the full model takes a few tenths of a second,
so a whole prediction (ten or so reduced runs) costs about one percent of one trajectory run of the
scene (docs/theory.md measures it).
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from typing import TYPE_CHECKING, Any

import numpy as np

from ...run import (
    CONVERGENCE_THRESHOLD,
    PreparedProjectile,
    impact_positions,
    initial_attitude,
    initial_state,
    prepare_projectile,
)
from ...run.compiled import announce_compiling, use_numba_cache
from ...scene import InputError, Scene
from ..engine.search import Bracket, search
from ..speeds.instability import MAX_SPEED, UNSTABLE_TURN, disturbance_fix, raised_speeds, range_fix

if TYPE_CHECKING:
    from dynamics.pitch_plane import PlaneEnds, PlaneSteps

__all__ = [
    "ReducedModel",
    "ReducedRun",
    "Prediction",
    "predict",
    "reduced_critical",
    "check_supported",
    "RTOL",
    "RINGS",
]

RTOL = 1e-4  # the reduced runs' tolerance: the predicted speeds move by < 0.5 % to 1e-6 (docs/theory.md)
RINGS = {"nose_rings": 12, "shank_rings": 8, "face_rings": 4}
ASSUMPTIONS = (
    "a body of revolution moving in the vertical plane (no yaw, no roll or yaw rate)",
    "the scene's DAFL law, ramps and friction, integrated over the exact profile instead of the mesh",
    "a homogeneous target (no layers, no free-surface reduction), separation on",
    "the mass and transverse moment of inertia of the scene's projectile",
)


@dataclass(frozen=True)
class ReducedRun:
    """One run of the reduced model (m/s, deg; ``end`` one of ``dynamics.pitch_plane.END_REASONS``)."""

    speed: float
    end: str
    unstable: bool
    axis_angle_change: float
    max_attack_angle: float
    convergence_speed: float | None
    evaluations: int


class ReducedModel:
    """The reduced pitch-plane model of a scene's projectile and target.

    Parameters
    ----------
    scene : Scene
        An analytic projectile (any nose, measured profiles included) in a homogeneous target,
        disturbed in the vertical plane only; anything else is refused with an :class:`InputError`.
    prepared : PreparedProjectile
        Its mass properties (the run's, :func:`cases.run.prepare_projectile`).
    rtol : float
        The reduced runs' relative tolerance.
    rings : dict
        The rings' counts (:func:`fem_loads.kernels.rings.revolved_surface`).
    """

    def __init__(
        self, scene: Scene, prepared: PreparedProjectile, rtol: float = RTOL, rings: dict[str, int] | None = None
    ) -> None:
        check_supported(scene)
        use_numba_cache()
        from fem_loads.kernels.rings import revolved_surface, ring_data

        from ...run.pitch_plane_step import pitch_plane_trajectory

        self.scene, self.prepared = scene, prepared
        self._trajectory = pitch_plane_trajectory
        self.rtol = rtol
        self.surface = revolved_surface(prepared.profile, float(prepared.tip[0]), **(rings or RINGS))
        effects = scene.effects
        # the mesh load's own law and effects, on the rings (check_supported refused layers and tables)
        self.laws, self.effects = ring_data(scene.loads(prepared.quadrature), self.surface)
        self.mass = float(prepared.mass.mass)
        self.inertia = float(prepared.mass.inertia[1, 1])
        self.gravity = effects.gravity_acceleration if effects.gravity else 0.0

        # the run's own start (cases.run.initial_state) with its axis angle exactly (a straight impact: 0);
        # only the velocity depends on the impact speed
        state = initial_state(scene, prepared)
        axis_angle = math.radians(scene.impact.oblique_angle + scene.impact.attack_angle)
        self._start = np.array(
            [
                state.position[0],
                state.position[2],
                axis_angle,
                state.velocity[0],
                state.velocity[2],
                state.angular_velocity[1],
            ]
        )

    def start(self, speed: float) -> np.ndarray:
        """The planar state ``(X, Z, phi, v_X, v_Z, q)`` at impact with ``speed`` (m/s)."""
        state = self._start.copy()
        state[3:5] *= speed / self.scene.impact.speed
        return state

    def starts(self, speeds: np.ndarray, attack_angles: np.ndarray, oblique_angles: np.ndarray) -> np.ndarray:
        """The planar states at impact, shape ``(n, 6)``, for impact ``speeds`` (m/s) and attack and oblique angles
        (deg) in place of the scene's, with its pitch rate: the run's own start (:func:`cases.run.initial_state`)."""
        from dynamics.quaternion import rotation_matrices

        attack = np.asarray(attack_angles, dtype=float)
        attitudes = initial_attitude(np.asarray(oblique_angles, dtype=float), attack, 0.0)
        rotations = rotation_matrices(attitudes.reshape(-1, 4))
        positions = impact_positions(self.prepared, rotations)
        beta = np.radians(oblique_angles)
        return np.column_stack(
            [
                positions[:, 0],
                positions[:, 2],
                np.radians(np.asarray(oblique_angles) + attack),
                speeds * np.sin(beta),
                -speeds * np.cos(beta),
                np.full(len(speeds), self._start[5]),
            ]
        )

    def _controls(
        self, speed: Any, turn_limit: float, time_limit: float | None, stop_when_converged: bool
    ) -> tuple[PlaneSteps, PlaneEnds]:
        """The step control and ends of a reduced run at ``speed`` (m/s, a float; ``turn_limit`` in deg).  For an
        array of speeds, one entry per run where they depend on it: the scales then have shape ``(n, 6)``."""
        from dynamics.pitch_plane import PlaneEnds, PlaneSteps

        length, numerics = self.prepared.length, self.scene.numerics
        # absolute tolerances as the full model's error control sets them (cases.run.step_control)
        v = np.asarray(speed, dtype=float)
        scales = np.stack(np.broadcast_arrays(length, length, 0.01, v, v, 0.01 * v / length), axis=-1)
        return PlaneSteps(self.rtol, scales, 1e-3 * length / speed, math.inf), PlaneEnds(
            numerics.stop_speed_at(speed),
            numerics.time_limit if time_limit is None else time_limit,
            math.radians(turn_limit),
            math.radians(CONVERGENCE_THRESHOLD),
            0.1 * speed,
            stop_when_converged,
        )

    def run(
        self,
        speed: float,
        stop_when_converged: bool = True,
        turn_limit: float = math.inf,
        time_limit: float | None = None,
        start: np.ndarray | None = None,
    ) -> ReducedRun:
        """A reduced run from impact at ``speed`` (m/s) to its end (``turn_limit``: an axis turn that ends it, deg;
        ``time_limit``: s, the scene's by default; ``start``: a state of :meth:`starts` with this speed instead of
        the scene's)."""
        from dynamics.pitch_plane import END_REASONS, PlaneBody

        announce_compiling("pitch_plane_trajectory")
        outcome = self._trajectory(
            self.surface.rings,
            self.laws,
            self.effects,
            self.surface.outline,
            self.start(speed) if start is None else start,
            PlaneBody(self.mass, self.inertia, self.gravity),
            *self._controls(speed, turn_limit, time_limit, stop_when_converged),
        )
        end, _, _, turn, peak, _, converged, _, _, evaluations = outcome
        turn = math.degrees(turn)  # the run's axis_angle_change
        return ReducedRun(
            speed,
            END_REASONS[end],
            abs(turn) >= UNSTABLE_TURN,
            turn,
            math.degrees(peak),
            converged if converged >= 0.0 else None,
            int(evaluations),
        )

    def unstable(self, speeds: np.ndarray, starts: np.ndarray) -> np.ndarray:
        """Whether each reduced run turns unstable, from the rows of ``starts`` (:meth:`starts`) at ``speeds``
        (m/s): :meth:`run`'s ``unstable`` with ``turn_limit`` the unstable turn, for many runs in one compiled call
        (what sorting an ensemble's samples costs is then the runs alone)."""
        from dynamics.pitch_plane import PlaneBody

        from ...run.pitch_plane_step import pitch_plane_turns

        announce_compiling("pitch_plane_turns")
        speeds = np.asarray(speeds, dtype=float)
        steps, ends = self._controls(speeds, UNSTABLE_TURN, None, True)
        turns = pitch_plane_turns(
            self.surface.rings,
            self.laws,
            self.effects,
            self.surface.outline,
            np.ascontiguousarray(starts, dtype=float).reshape(-1, 6),
            PlaneBody(self.mass, self.inertia, self.gravity),
            (steps.rtol, steps.scales.reshape(-1, 6), np.asarray(steps.first_step), steps.max_step),
            (
                np.asarray(ends.stop_speed),
                ends.time_limit,
                ends.turn_limit,
                ends.threshold,
                np.asarray(ends.peak_floor),
                ends.stop_when_converged,
            ),
        )
        return np.abs(np.degrees(turns)) >= UNSTABLE_TURN


@dataclass
class Prediction:
    """What :func:`predict` returns (m/s, s)."""

    characteristic_convergent_velocity: float | None
    critical_velocity: float | None
    critical_bracket: list[float] | None
    model: str
    assumptions: list[str]
    runs: list[ReducedRun] = field(default_factory=list)
    messages: list[str] = field(default_factory=list)
    prediction_time: float = 0.0
    wall_time: float = 0.0

    def as_dict(self) -> dict:
        record = asdict(self)
        record["runs"] = [asdict(run) for run in self.runs]
        return record


def predict(
    scene: Scene,
    speeds: tuple[float, float] = (200.0, 1600.0),
    resolution: float = 5.0,
    rtol: float = RTOL,
    rings: dict[str, int] | None = None,
) -> Prediction:
    """The characteristic convergent velocity and the critical impact velocity of ``scene`` (its disturbance).

    ``speeds``: the range the critical velocity is sought in, and ``resolution`` its bracket (m/s), as
    ``penetrate critical`` takes them; ``rtol`` and ``rings``: the model's numerics (:class:`ReducedModel`).
    ``prediction_time`` is the model's own cost (from the prepared
    projectile on: comparable with a run's ``integration_time``); ``wall_time`` includes preparing the
    projectile (the mesh and mass properties a run prepares too; read from the cache when there).
    """
    start = time.perf_counter()
    model = ReducedModel(scene, prepare_projectile(scene), rtol, rings)
    model.run(scene.impact.speed, time_limit=0.0)  # numba loads (or compiles) its code here, outside the timing
    clock = time.perf_counter()
    runs: list[ReducedRun] = []
    messages: list[str] = []
    convergent = _convergent(model, scene.impact.speed, runs, messages)
    critical, bracket = _critical(model, speeds, resolution, runs, messages, convergent)
    end = time.perf_counter()
    description = (
        f"reduced pitch-plane model: the scene's DAFL integrated over {len(model.surface.rings)} rings of"
        f" the exact profile, a planar rigid body, Dormand-Prince rtol {rtol:g} (docs/theory.md)"
    )
    return Prediction(
        convergent, critical, bracket, description, list(ASSUMPTIONS), runs, messages, end - clock, end - start
    )


def _convergent(model: ReducedModel, impact_speed: float, runs: list[ReducedRun], messages: list[str]) -> float | None:
    """The convergence speed of the first unstable reduced run, from the scene's speed up by 15 % steps."""
    for speed in raised_speeds(impact_speed):
        run = model.run(speed)
        runs.append(run)
        if run.unstable:
            break
    else:
        messages.append(
            f"no unstable reduced run up to {MAX_SPEED:g} m/s: no characteristic convergent velocity;"
            f" {disturbance_fix(model.scene)}"
        )
        return None
    if speed != model.scene.impact.speed:
        messages.append(
            f"the reduced run at {model.scene.impact.speed:g} m/s is stable; the convergent velocity is"
            f" that of the run at {speed:.6g} m/s"
        )
    if run.convergence_speed is None:
        # the reduced model's threshold is fixed; the measured velocity takes another (penetrate convergent)
        messages.append(
            f"the attack angle of the reduced run at {speed:.6g} m/s never fell below {CONVERGENCE_THRESHOLD} deg:"
            " measure the convergent velocity at a larger threshold with penetrate convergent --threshold"
        )
    return run.convergence_speed


def reduced_critical(model: ReducedModel, speeds: tuple[float, float], resolution: float) -> tuple[float | None, bool]:
    """The reduced model's critical impact velocity in ``speeds`` (m/s), to ``resolution``, from nothing known;
    None when the range holds no change, with whether its runs were then stable throughout (else unstable down
    to the range's bottom)."""
    runs: list[ReducedRun] = []
    critical, _ = _critical(model, speeds, resolution, runs, [], None)
    return critical, critical is None and not any(run.unstable for run in runs)


def _critical(
    model: ReducedModel,
    speeds: tuple[float, float],
    resolution: float,
    runs: list[ReducedRun],
    messages: list[str],
    convergent: float | None,
) -> tuple[float | None, list[float] | None]:
    """The change from stable to unstable reduced runs (each stops at the 30-degree turn that makes it unstable,
    or once its attack angle has converged) in ``speeds``, by the one threshold search of the full runs
    (:func:`~cases.studies.engine.search.search`), one run a round.

    The first bracket uses the runs already made (``runs``: the convergent velocity's): the lowest unstable one
    in the range is an upper end and the highest stable one below it a lower end.  Without a stable run, no run
    below the convergent velocity can turn unstable (its attack angle collapses at once), so that is the assumed
    lower end; a run that contradicts it moves the end to the range's bottom.
    """
    low, high = float(min(speeds)), float(max(speeds))
    bracket = Bracket(
        low,
        high,
        (low, high),
        resolution,
        failures=(
            "no unstable reduced run up to {speed:g} m/s: no critical impact velocity in the range; "
            + range_fix(True, speeds, model.scene).replace("{", "{{").replace("}", "}}"),
            "the reduced run at {speed:g} m/s is already unstable: the critical impact velocity lies below the"
            " range; " + range_fix(False, speeds, model.scene).replace("{", "{{").replace("}", "}}"),
        ),
    )
    known = {run.speed: run.unstable for run in runs if low <= run.speed <= high}
    if known:
        bracket.update(known)
    if not bracket.low_run and convergent is not None and bracket.low < convergent < bracket.high:
        bracket.low = convergent

    def scan(wanted: list[list[float]]) -> list[dict[float, bool]]:
        for speed in wanted[0]:
            if speed not in known:
                run = model.run(speed, turn_limit=UNSTABLE_TURN)
                runs.append(run)
                known[speed] = run.unstable
        return [known]

    search([bracket], 1, scan)
    if bracket.failure:
        messages.append(bracket.failure)
        return None, None
    return bracket.middle, [bracket.low, bracket.high]


def check_supported(scene: Scene) -> None:
    """One line naming what the reduced model cannot take, with what it needs."""
    projectile, effects, impact = scene.projectile, scene.effects, scene.impact
    if projectile.geometry is not None:
        raise InputError(
            "projectile.geometry: penetrate predict needs a body of revolution given by its profile"
            " (diameter, length, nose); a projectile read from a file is run by penetrate critical"
        )
    from fem_loads.target import LayeredTarget

    law = scene.target.build()
    if isinstance(law, LayeredTarget):
        raise InputError("target.layers: penetrate predict needs a homogeneous target (one law); drop the layers")
    if getattr(law, "strength_table", None):
        raise InputError(
            "target.law.strength_table: penetrate predict takes strength that grows with depth as depth_gradient"
            " only; drop the table (penetrate critical runs it)"
        )
    if scene.target.inclination != 0.0:
        raise InputError(
            "target.inclination: penetrate predict needs a level target (inclination 0); the same shot into a"
            " level target has impact.oblique_angle + inclination as its oblique angle"
        )
    if effects.free_surface is not None:
        raise InputError("effects.free_surface: penetrate predict has no free-surface reduction; drop it")
    if not effects.separation:
        raise InputError("effects.separation = false: penetrate predict needs separation (the DAFL's default)")
    if impact.yaw_angle != 0.0 or impact.angular_velocity[0] != 0.0 or impact.angular_velocity[2] != 0.0:
        raise InputError(
            "impact.yaw_angle and impact.angular_velocity[0], [2] must be 0: penetrate predict models"
            " motion in the vertical plane (attack angle, oblique angle, pitch rate)"
        )
