"""The typed summary of a run, the outputs of ``penetrate run --out``, and a run as the run store keeps it."""

from __future__ import annotations

import io
import math
import os
from collections.abc import Mapping
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Annotated, Any, NamedTuple

import numpy as np
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field

from dynamics.quaternion import rotation_matrix

from ..scene import Numerics, Scene
from .history import ATTACK_ANGLE_SPEED_FRACTION, HISTORY_UNITS, attack_angle_peak, history_columns, history_csv
from .persistence import atomic_write, atomic_write_text, json_safe, json_text
from .runner import (
    COARSE_ERROR,
    COARSE_TURN,
    EXITED,
    PERFORATED,
    RICOCHETED,
    STOPPED,
    WARN_SHARE,
    RunResult,
    run_scene,
)

if TYPE_CHECKING:
    import pandas as pd

    from .prepare import PreparedProjectile

__all__ = [
    "RunSummary",
    "summarise",
    "run_warnings",
    "write_outputs",
    "StoredRun",
    "simulate_record",
    "MAX_STORED_HISTORY_ROWS",
    "WARN_SHARE",
]

# a Dormand-Prince tolerance above this is warned of: the integration error alone can reach per cents
LOOSE_RTOL = 1e-3
MAX_STORED_HISTORY_ROWS = 4000  # histories in a run store are thinned to about this many rows


def _nan_for_null(value: Any) -> Any:
    return math.nan if value is None else value


# a float that JSON writes as null when it is not finite, and reads back from null as NaN
Real = Annotated[float, BeforeValidator(_nan_for_null)]


def _quantity(unit: str, description: str) -> Any:
    return Field(description=description, json_schema_extra={"unit": unit})


class RunSummary(BaseModel):
    """The headline numbers of a run (SI units, angles in degrees).

    What the command line prints, ``summary.json`` holds, a sweep table has per row,
    and the studies and the paper read.  Each number's unit is in its field's
    ``json_schema_extra["unit"]``.
    """

    model_config = ConfigDict(extra="forbid", frozen=True)

    scene: str = Field(description="the scene's name")
    depth: Real = _quantity("m", "largest depth of the nose tip below the surface")
    path_length: Real = _quantity("m", "distance travelled by the centre of mass")
    end_reason: str = Field(
        description="stopped, exited, perforated, ricocheted, time_limit, non_finite, step_floor or max_steps"
    )
    final_time: Real = _quantity("s", "time at the end of the run")
    final_speed: Real = _quantity("m/s", "speed at the end of the run")
    final_position: list[Real] = _quantity("m", "centre of mass at the end, world frame")
    max_attack_angle: Real = _quantity(
        "deg",
        f"largest total attack angle while the speed is at least {ATTACK_ANGLE_SPEED_FRACTION:g} of the impact speed",
    )
    final_attack_angle: Real = _quantity("deg", "signed attack angle in the vertical plane at the end")
    axis_angle_change: Real = _quantity("deg", "turn of the axis in the vertical plane over the run")
    residual_velocity: Real = Field(
        math.nan, description="speed after perforation (NaN unless perforated)", json_schema_extra={"unit": "m/s"}
    )
    exit_time: Real = Field(
        math.nan,
        description="when the whole body left the target: perforated, exited or ricocheted (NaN otherwise)",
        json_schema_extra={"unit": "s"},
    )
    exit_axis_angle: Real = Field(
        math.nan,
        description="at exit, the axis's angle from the outward normal of the face it left through",
        json_schema_extra={"unit": "deg"},
    )
    exit_velocity_angle: Real = Field(
        math.nan,
        description="at exit, the velocity's angle from the outward normal of the face it left through",
        json_schema_extra={"unit": "deg"},
    )
    exit_attack_angle: Real = Field(
        math.nan, description="at exit, the angle between the axis and the velocity", json_schema_extra={"unit": "deg"}
    )
    wall_time: Real = _quantity("s", "the whole run, preparation included")
    integration_time: Real = _quantity("s", "the time integration alone")
    mass: Real = _quantity("kg", "mass of the projectile")
    centre_of_mass_from_tip: Real = _quantity("m", "centre of mass behind the nose tip")
    axial_inertia: Real = _quantity("kg m^2", "moment of inertia about the axis")
    transverse_inertia: Real = _quantity("kg m^2", "moment of inertia about a transverse axis")
    surface_points: int = _quantity("1", "surface quadrature points")
    tetrahedra: int = _quantity("1", "tetrahedra of the mesh")
    steps: int | None = _quantity("1", "accepted steps")
    rejected_steps: int | None = _quantity("1", "steps retaken by the error control")
    forced_steps: int | None = _quantity(
        "1", "steps accepted above the tolerance at the error control's shortest step (numerics.time_step)"
    )
    energy_rejections: int | None = _quantity("1", "steps retaken by the energy guard")
    energy_projections: int | None = _quantity("1", "accepted states whose sub-tolerance energy gain was removed")
    load_evaluations: int | None = _quantity("1", "calls of the load function")
    warnings: list[str] = Field(description="plain-language doubts about the run's numerics")

    @classmethod
    def from_record(cls, record: dict) -> RunSummary:
        """The summary in a stored record (which also holds the resolved scene)."""
        return cls.model_validate({k: v for k, v in record.items() if k in cls.model_fields})

    def record(self) -> dict:
        """The summary as a JSON-ready dictionary (non-finite numbers as None)."""
        return json_safe(self.model_dump())


def summarise(result: RunResult, history: pd.DataFrame | Mapping[str, np.ndarray] | None = None) -> RunSummary:
    """The run's :class:`RunSummary` (``history``: its :func:`~.history.history_columns` or
    :func:`~.history.history_table`, computed if not given)."""
    h = history_columns(result) if history is None else history

    def column(name: str) -> np.ndarray:
        return np.asarray(h[name])

    mass = result.prepared.mass
    stats = result.trajectory.statistics
    leaving = exit_quantities(result)
    return RunSummary(
        scene=result.scene.name,
        depth=float(np.max(column("tip_depth"))),
        path_length=float(column("path_length")[-1]),
        end_reason=result.trajectory.end_reason,
        final_time=float(column("time")[-1]),
        final_speed=float(column("speed")[-1]),
        final_position=[float(column(f"position_{c}")[-1]) for c in "xyz"],
        max_attack_angle=float(column("total_attack_angle")[attack_angle_peak(h)]),
        final_attack_angle=float(column("attack_angle")[-1]),
        axis_angle_change=float(column("axis_angle")[-1] - column("axis_angle")[0]),
        residual_velocity=leaving.residual_velocity,
        exit_time=leaving.exit_time,
        exit_axis_angle=leaving.exit_axis_angle,
        exit_velocity_angle=leaving.exit_velocity_angle,
        exit_attack_angle=leaving.exit_attack_angle,
        wall_time=result.wall_time,
        integration_time=result.integration_time,
        mass=mass.mass,
        centre_of_mass_from_tip=mass.centre_from_tip,
        axial_inertia=mass.axial_inertia,
        transverse_inertia=mass.transverse_inertia,
        surface_points=len(result.prepared.quadrature),
        tetrahedra=result.prepared.n_tetra,
        **{
            name: stats.get(name)
            for name in (
                "steps",
                "rejected_steps",
                "forced_steps",
                "energy_rejections",
                "energy_projections",
                "load_evaluations",
            )
        },
        warnings=run_warnings(result.trajectory.end_reason, stats)
        + result.scene.warnings
        + numerics_warnings(result.scene.numerics)
        + entry_warnings(result.scene, result.prepared.nose_length)
        + axis_warnings(result.prepared),
    )


class ExitQuantities(NamedTuple):
    """The summary's exit fields (:class:`RunSummary`), NaN for a run that did not leave the target."""

    residual_velocity: float = math.nan
    exit_time: float = math.nan
    exit_axis_angle: float = math.nan
    exit_velocity_angle: float = math.nan
    exit_attack_angle: float = math.nan


def exit_quantities(result: RunResult) -> ExitQuantities:
    """The exit fields of a run that left the target (``residual_velocity`` after perforation alone): its final
    state, where the exit event ended it."""
    end, trajectory = result.trajectory.end_reason, result.trajectory
    if end not in (PERFORATED, EXITED, RICOCHETED):
        return ExitQuantities()
    inward = -np.asarray(result.scene.target.face.normal)
    outward = inward if end == PERFORATED else -inward  # the rear face's outward normal, or the front face's
    axis = rotation_matrix(trajectory.attitude[-1])[:, 0]
    velocity = trajectory.velocity[-1]
    speed = float(np.linalg.norm(velocity))
    direction = velocity / speed if speed > 0.0 else velocity

    def angle(a: np.ndarray, b: np.ndarray) -> float:
        return math.degrees(math.acos(min(1.0, max(-1.0, float(a @ b)))))

    moving = speed > 0.0  # a body at rest has no direction of motion
    return ExitQuantities(
        speed if end == PERFORATED else math.nan,
        float(trajectory.time[-1]),
        angle(axis, outward),
        angle(direction, outward) if moving else math.nan,
        angle(axis, direction) if moving else math.nan,
    )


def numerics_warnings(numerics: Numerics) -> list[str]:
    """What a scene's numerics alone make doubtful: flat facets with their own normals (first-order geometry,
    mesh normals) tilt every normal by up to half the angle between neighbouring facets, and the depth comes
    out short by several per cent (docs/geometry.md, faceted surfaces); a loose Dormand-Prince tolerance."""
    if numerics.geometry_order == 1 and numerics.normals == "mesh":
        return [
            'flat facets with their own normals (numerics.geometry_order = 1, normals = "mesh"): test 2\'s'
            " depth comes out 7 % short at 20 mm facets, 2.4 % at 10 mm, 0.8 % at 5 mm; second-order"
            " tetrahedra give 0.3 %, 0.1 %, 0.03 % (against the exact 1-D integration; docs/geometry.md, faceted"
            " surfaces)"
        ]
    if numerics.integrator == "dopri54" and numerics.rtol > LOOSE_RTOL:
        return [
            f"numerics.rtol = {numerics.rtol:g} is loose: above {LOOSE_RTOL:g} the integration error alone can"
            " reach per cents of the depth (docs/accuracy.md gives the settings that meet an accuracy)"
        ]
    return []


def axis_warnings(prepared: PreparedProjectile) -> list[str]:
    """A body from a file whose axis of least inertia lies more than :data:`~mesh.imported.AXIS_TOLERANCE`
    degrees from the axis the scene declares (``projectile.geometry.axis``): a long body declared along the
    wrong direction flies broadside.  Bodies without a clear long axis (the two smallest moments within 10 %)
    are not judged; a body read without an axis was refused before meshing if its axis was off."""
    from mesh.imported import AXIS_TOLERANCE, LONG_AXIS, FileGeometry

    geometry = prepared.geometry
    if not isinstance(geometry, FileGeometry):
        return []
    moments, axes = np.linalg.eigh(prepared.mass.inertia)
    if not moments[0] < LONG_AXIS * moments[1]:
        return []
    angle = math.degrees(math.acos(min(1.0, abs(float(axes[0, 0]) / float(np.linalg.norm(axes[:, 0]))))))
    if angle <= AXIS_TOLERANCE:
        return []
    # the body frame is the file's turned by the geometry's rotation: back to the file's coordinates
    in_file = geometry.rotation.T @ axes[:, 0]
    in_file = in_file * np.sign(in_file[np.argmax(np.abs(in_file))])
    in_file = np.where(np.abs(in_file) < 1e-4, 0.0, in_file)  # the mesh's round-off in the components
    shown = "[" + ", ".join(f"{v:.3g}" for v in in_file + 0.0) + "]"
    declared = "[" + ", ".join(f"{v:.4g}" for v in geometry.rotation[0] + 0.0) + "]"
    return [
        f"projectile.geometry.axis = {declared}: the body's axis of least inertia lies {angle:.1f} deg"
        f" from it, along {shown} in the file: a long body declared along another direction flies sideways;"
        f" say axis = {shown}, the direction from tail to tip (its opposite if the tip is at the other end), or"
        ' axis = "auto"'
    ]


def entry_warnings(scene: Scene, nose_length: float) -> list[str]:
    """A fixed step that carries the body further than its nose at the impact speed cannot follow the nose's
    entry, where the load grows from nothing to its full value: the stages of the first steps see the body
    far inside, or not yet in, and such runs can end many per cent off, however many steps follow."""
    numerics = scene.numerics
    if numerics.integrator != "rk4":
        return []
    travel = numerics.time_step * scene.impact.speed
    if travel <= nose_length:
        return []
    return [
        f"numerics.time_step = {numerics.time_step:g} s carries the body {travel:.3g} m in a step at the impact speed,"
        f" more than its nose ({nose_length:.3g} m): the entry is not resolved; take at most"
        f' {nose_length / scene.impact.speed:.2g} s, or numerics.integrator = "dopri54" (docs/numerics.md, the end'
        " of a run)"
    ]


def run_warnings(end_reason: str, statistics: dict) -> list[str]:
    """Plain-language warnings about a run's numerics (empty when nothing needs saying).

    A run that ends by a numerical failure or the time limit, or whose steps were
    often retaken by the energy guard or accepted above the adaptive tolerance,
    still returns its numbers; these lines say why they deserve suspicion.
    """
    steps = max(1, int(statistics.get("steps") or 0))
    warnings = []
    if end_reason not in (STOPPED, EXITED, PERFORATED, RICOCHETED):
        warnings.append(f"the run ended by {end_reason}, not by stopping or leaving the target")
    retaken = int(statistics.get("energy_rejections") or 0)
    if retaken > WARN_SHARE * steps:
        warnings.append(
            f"{retaken} retakes by the energy guard for {steps} steps: numerics.time_step is too coarse"
            " for this scene (docs/numerics.md, the energy guard)"
        )
    error = statistics.get("coarse_step_error")
    turn = statistics.get("coarse_step_turn") or 0.0
    if error is not None and (error > COARSE_ERROR or turn > COARSE_TURN):
        if not math.isfinite(error):
            moved = "ends otherwise"
        else:
            moved = f"moves the depth or the path length by {error:.1%} and the final axis by {turn:.2g} deg"
        warnings.append(
            f"only {steps} fixed steps, and the same run at half numerics.time_step {moved}: the step is too"
            " coarse to trust this run's figures to better than that (shorten it, or use numerics.integrator ="
            ' "dopri54"; docs/numerics.md, the end of a run)'
        )
    forced = int(statistics.get("forced_steps") or 0)
    if forced > WARN_SHARE * steps:
        warnings.append(
            f"{forced} of {steps} steps accepted above the tolerance at the shortest step (numerics.time_step): the"
            " error control cannot meet numerics.rtol here (docs/numerics.md, hard cases)"
        )
    return warnings


def write_outputs(
    result: RunResult,
    out_dir: str | os.PathLike,
    every: int = 1,
    history: pd.DataFrame | Mapping[str, np.ndarray] | None = None,
) -> dict[str, Path]:
    """Write ``summary.json`` (with the resolved scene) and ``history.csv`` into ``out_dir``.

    Each file is written atomically, and ``summary.json`` last: a run killed at
    any moment leaves each file complete or absent, and a ``summary.json``
    always belongs with the ``history.csv`` beside it.  A previous run's
    ``summary.json`` in ``out_dir`` is removed first (and its ``history.csv``
    when this run writes none), so files of two runs never mix.  Non-finite
    numbers are written as JSON ``null`` and as empty CSV cells.
    """
    out = Path(out_dir)
    h = history_columns(result) if history is None else history
    record = summarise(result, h).record()
    record["scene_resolved"] = result.scene.model_dump(mode="json")
    record["history_units"] = HISTORY_UNITS
    text = json_text(record, indent=2) + "\n"  # before anything is removed: a record JSON cannot hold writes nothing
    paths = {"summary": out / "summary.json"}
    (out / "summary.json").unlink(missing_ok=True)
    if result.scene.outputs.history:
        paths["history"] = atomic_write(out / "history.csv", history_csv(h, every))
    else:
        (out / "history.csv").unlink(missing_ok=True)
    atomic_write_text(paths["summary"], text)
    return paths


@dataclass(frozen=True)
class StoredRun:
    """A run as a run store keeps it: its summary, or the error that ended it."""

    key: str
    summary: RunSummary | None
    error: str | None

    @classmethod
    def from_record(cls, key: str, record: dict | None) -> StoredRun:
        if record is None:
            return cls(key, None, "not run")
        if "error" in record:
            return cls(key, None, str(record["error"]))
        return cls(key, RunSummary.from_record(record), None)

    @property
    def failed(self) -> bool:
        return self.summary is None


def simulate_record(scene_json: str) -> tuple[dict, bytes | None]:
    """Run one resolved scene (a worker's job): its stored record and gzipped CSV history, or the error.

    The record is the summary and the resolved scene; the history is thinned to about
    :data:`MAX_STORED_HISTORY_ROWS` rows (the last row always kept).
    """
    scene = Scene.model_validate_json(scene_json)
    try:
        result = run_scene(scene)
        history = history_columns(result)
        record = summarise(result, history).record()
        record["scene_resolved"] = scene.model_dump(mode="json")
    except Exception as exc:  # recorded, so that one failure does not stop the sweep
        return {"error": f"{type(exc).__name__}: {exc}"}, None
    import gzip  # a study's worker only

    buffer = io.BytesIO()
    # level 1: a seventh of level 9's time on a run's history, for a file 7 % larger
    with gzip.GzipFile(fileobj=buffer, mode="wb", compresslevel=1, mtime=0) as gz:
        gz.write(history_csv(history, max(1, len(history["time"]) // MAX_STORED_HISTORY_ROWS)))
    return record, buffer.getvalue()
