"""Time histories and summaries of a run, and writing them atomically."""

from __future__ import annotations

import contextlib
import json
import math
import os
import re
import tempfile
from pathlib import Path

import numpy as np
import pandas as pd

from dynamics.quaternion import rotation_matrix

from .runner import RunResult

__all__ = ["history_table", "summary", "write_outputs", "atomic_write_text", "atomic_write_bytes", "json_safe", "attack_angle_peak", "HISTORY_UNITS"]

ATTACK_ANGLE_SPEED_FRACTION = 0.1

HISTORY_UNITS = {
    "time": "s",
    "position_x": "m", "position_y": "m", "position_z": "m",
    "velocity_x": "m/s", "velocity_y": "m/s", "velocity_z": "m/s",
    "speed": "m/s", "path_length": "m", "tip_depth": "m",
    "attitude_w": "1", "attitude_x": "1", "attitude_y": "1", "attitude_z": "1",
    "angular_velocity_x": "rad/s", "angular_velocity_y": "rad/s", "angular_velocity_z": "rad/s",
    "axis_angle": "deg", "velocity_angle": "deg", "attack_angle": "deg", "total_attack_angle": "deg",
    "force_x": "N", "force_y": "N", "force_z": "N",
    "moment_x": "N m", "moment_y": "N m", "moment_z": "N m",
    "resistance_centre_from_tip": "m",
}


def attack_angle_peak(history: pd.DataFrame) -> int:
    """Row (position) of the largest total attack angle while the speed is at least
    :data:`ATTACK_ANGLE_SPEED_FRACTION` of the impact speed (near rest the angle means nothing)."""
    speed = history["speed"].to_numpy()
    angle = history["total_attack_angle"].to_numpy()
    moving = np.flatnonzero(speed >= ATTACK_ANGLE_SPEED_FRACTION * speed[0])
    return int(moving[np.argmax(angle[moving])])


def _plane_angle(vectors: np.ndarray) -> np.ndarray:
    """Angle (deg) in the vertical plane from the inward normal -Z towards +X, unwrapped along the run."""
    return np.degrees(np.unwrap(np.arctan2(vectors[:, 0], -vectors[:, 2])))


def history_table(result: RunResult) -> pd.DataFrame:
    """One row per recorded step; the columns and their units are :data:`HISTORY_UNITS`.

    ``attack_angle`` is signed in the vertical plane (``axis_angle -
    velocity_angle``); ``total_attack_angle`` is the unsigned 3-D angle between
    the axis and the velocity.  ``resistance_centre_from_tip`` is the point R on
    the axis with ``M = R x F`` (least squares over the transverse force),
    measured back from the nose tip; it is empty when the transverse force
    vanishes.
    """
    tr = result.trajectory
    rotation = np.array([rotation_matrix(q) for q in tr.attitude])
    axis = rotation[:, :, 0]
    tip = tr.position + rotation @ result.prepared.tip
    speed = np.linalg.norm(tr.velocity, axis=1)
    direction = tr.velocity / np.where(speed > 0, speed, 1.0)[:, None]
    total_attack = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", axis, direction), -1.0, 1.0)))
    axis_angle = _plane_angle(axis)
    velocity_angle = _plane_angle(tr.velocity)
    attack = (axis_angle - velocity_angle + 180.0) % 360.0 - 180.0
    force_body = np.einsum("nji,nj->ni", rotation, tr.force)
    transverse2 = force_body[:, 1] ** 2 + force_body[:, 2] ** 2
    ahead = (tr.moment[:, 2] * force_body[:, 1] - tr.moment[:, 1] * force_body[:, 2])
    defined = transverse2 > (1e-9 * np.linalg.norm(force_body, axis=1)) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        centre = np.where(defined, result.prepared.mass.centre_from_tip - ahead / transverse2, np.nan)
    columns = {
        "time": tr.time,
        "position_x": tr.position[:, 0], "position_y": tr.position[:, 1], "position_z": tr.position[:, 2],
        "velocity_x": tr.velocity[:, 0], "velocity_y": tr.velocity[:, 1], "velocity_z": tr.velocity[:, 2],
        "speed": speed, "path_length": tr.path_length, "tip_depth": -tip[:, 2],
        "attitude_w": tr.attitude[:, 0], "attitude_x": tr.attitude[:, 1],
        "attitude_y": tr.attitude[:, 2], "attitude_z": tr.attitude[:, 3],
        "angular_velocity_x": tr.angular_velocity[:, 0], "angular_velocity_y": tr.angular_velocity[:, 1],
        "angular_velocity_z": tr.angular_velocity[:, 2],
        "axis_angle": axis_angle, "velocity_angle": velocity_angle,
        "attack_angle": attack, "total_attack_angle": total_attack,
        "force_x": tr.force[:, 0], "force_y": tr.force[:, 1], "force_z": tr.force[:, 2],
        "moment_x": tr.moment[:, 0], "moment_y": tr.moment[:, 1], "moment_z": tr.moment[:, 2],
        "resistance_centre_from_tip": centre,
    }
    return pd.DataFrame(columns)


def summary(result: RunResult, history: pd.DataFrame | None = None) -> dict:
    """The run's headline numbers (SI units, angles in degrees).

    ``depth`` is the largest depth of the nose tip below the surface,
    ``path_length`` the distance travelled by the centre of mass,
    ``max_attack_angle`` the largest total attack angle while the speed is at
    least :data:`ATTACK_ANGLE_SPEED_FRACTION` of the impact speed, and
    ``axis_angle_change`` the change of the axis angle in the vertical plane.
    """
    h = history_table(result) if history is None else history
    mass = result.prepared.mass
    stats = result.trajectory.statistics
    first, last = h.iloc[0], h.iloc[-1]
    return {
        "scene": result.scene.name,
        "depth": float(h["tip_depth"].max()),
        "path_length": float(last["path_length"]),
        "end_reason": result.trajectory.end_reason,
        "final_time": float(last["time"]),
        "final_speed": float(last["speed"]),
        "final_position": [float(last[f"position_{c}"]) for c in "xyz"],
        "max_attack_angle": float(h["total_attack_angle"].iloc[attack_angle_peak(h)]),
        "final_attack_angle": float(last["attack_angle"]),
        "axis_angle_change": float(last["axis_angle"] - first["axis_angle"]),
        "wall_time": result.wall_time,
        "integration_time": result.integration_time,
        "mass": mass.mass,
        "centre_of_mass_from_tip": mass.centre_from_tip,
        "axial_inertia": mass.axial_inertia,
        "transverse_inertia": mass.transverse_inertia,
        "surface_points": len(result.prepared.quadrature),
        "tetrahedra": result.prepared.n_tetra,
        "steps": stats.get("steps"),
        "rejected_steps": stats.get("rejected_steps"),
        "forced_steps": stats.get("forced_steps"),
        "energy_rejections": stats.get("energy_rejections"),
        "energy_projections": stats.get("energy_projections"),
        "load_evaluations": stats.get("load_evaluations"),
        "warnings": run_warnings(result.trajectory.end_reason, stats),
    }


# a share of steps above which retaken or forced steps mean the numerics do not suit the scene
WARN_SHARE = 0.1


def run_warnings(end_reason: str, statistics: dict) -> list[str]:
    """Plain-language warnings about a run's numerics (empty when nothing needs saying).

    A run that ends by a numerical failure or the time limit, or whose steps were
    often retaken by the energy guard or accepted above the adaptive tolerance,
    still returns its numbers; these lines say why they deserve suspicion.
    """
    steps = max(1, int(statistics.get("steps") or 0))
    warnings = []
    if end_reason not in ("stopped", "exited"):
        warnings.append(f"the run ended by {end_reason}, not by stopping or leaving the target")
    retaken = int(statistics.get("energy_rejections") or 0)
    if retaken > WARN_SHARE * steps:
        warnings.append(f"{retaken} retakes by the energy guard for {steps} steps: numerics.time_step is too coarse"
                        " for this scene (docs/numerics.md, the energy guard)")
    forced = int(statistics.get("forced_steps") or 0)
    if forced > WARN_SHARE * steps:
        warnings.append(f"{forced} of {steps} steps accepted above the tolerance at the step floor: the error control"
                        " cannot meet numerics.rtol here (docs/numerics.md, hard cases)")
    return warnings


def _umask() -> int:
    """The process's umask, read without changing it where the system tells it (Linux)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write_bytes(path: Path, data: bytes) -> None:
    """Write ``data`` to ``path`` through a synced temporary file renamed into place.

    A reader (or a process killed at any moment) sees the old file or the new
    one, never a part.  A kill can leave the hidden temporary file
    ``.NAME.PID.*.tmp`` beside it, never a partial file under the final name;
    a later write of the same file removes those of processes that no longer
    run (:func:`remove_stale_temporaries`).  The file gets the usual permissions (``0666`` less the umask), not
    the temporary file's ``0600``.
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    remove_stale_temporaries(path)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.{os.getpid()}.", suffix=".tmp")
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fchmod(f.fileno(), 0o666 & ~_umask())
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    try:  # make the rename itself durable
        directory = os.open(path.parent, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(directory)
    except OSError:
        pass
    finally:
        os.close(directory)


def _running(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except OSError:  # exists, owned by someone else
        return True
    return True


# the temporaries of dead writers in each folder this process has written into, by the name they
# were for: a folder is listed once per process, not at every write (a run store holds thousands
# of files, and listing it cost 19 ms per write at 20 000)
_STALE_TEMPORARIES: dict[Path, dict[str, list[Path]]] = {}
_TEMPORARY_NAME = re.compile(r"^\.(?P<name>.+)\.(?P<pid>\d+)\.[^.]+\.tmp$")


def _dead_writers_temporaries(folder: Path) -> dict[str, list[Path]]:
    stale: dict[str, list[Path]] = {}
    with contextlib.suppress(OSError):
        for entry in os.scandir(folder):
            match = _TEMPORARY_NAME.match(entry.name)
            if match and not _running(int(match["pid"])):
                stale.setdefault(match["name"], []).append(Path(entry.path))
    return stale


def remove_stale_temporaries(path: Path) -> list[Path]:
    """Remove the temporary files of :func:`atomic_write_bytes` for ``path`` left by killed processes.

    Only files named ``.NAME.PID.*.tmp`` whose process no longer runs are removed
    (a live writer's file is left alone).  The folder is listed at this process's
    first write into it; temporaries left later by other killed processes wait for
    the next process.  Returns the removed paths.
    """
    path = Path(path)
    folder = Path(os.path.abspath(path.parent))  # one entry per folder however it is named
    if folder not in _STALE_TEMPORARIES:
        _STALE_TEMPORARIES[folder] = _dead_writers_temporaries(folder)
    removed = _STALE_TEMPORARIES[folder].pop(path.name, [])
    for tmp in removed:
        tmp.unlink(missing_ok=True)
    return removed


def save_figure(figure, path: str | os.PathLike, dpi: int = 110) -> Path:
    """Save a matplotlib figure as PNG atomically (:func:`atomic_write_bytes`)."""
    import io

    buffer = io.BytesIO()
    figure.savefig(buffer, format="png", dpi=dpi)
    atomic_write_bytes(Path(path), buffer.getvalue())
    return Path(path)


def atomic_write_text(path: Path, text: str) -> None:
    """:func:`atomic_write_bytes` of UTF-8 text."""
    atomic_write_bytes(path, text.encode("utf-8"))


def json_safe(value):
    if isinstance(value, float) and not math.isfinite(value):
        return None
    if isinstance(value, dict):
        return {k: json_safe(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [json_safe(v) for v in value]
    return value


def write_outputs(result: RunResult, out_dir: str | os.PathLike, every: int = 1,
                  history: pd.DataFrame | None = None) -> dict[str, Path]:
    """Write ``summary.json`` (with the resolved scene) and ``history.csv`` into ``out_dir``.

    Each file is written atomically, and ``summary.json`` last: a run killed at
    any moment leaves each file complete or absent, and a ``summary.json``
    always belongs with the ``history.csv`` beside it.  A previous run's
    ``summary.json`` in ``out_dir`` is removed first (and its ``history.csv``
    when this run writes none), so files of two runs never mix.  Non-finite
    numbers are written as JSON ``null`` and as empty CSV cells.
    """
    out = Path(out_dir)
    h = history_table(result) if history is None else history
    record = summary(result, h)
    record["scene_resolved"] = result.scene.model_dump(mode="json")
    record["history_units"] = HISTORY_UNITS
    text = json.dumps(json_safe(record), indent=2, allow_nan=False) + "\n"
    paths = {"summary": out / "summary.json"}
    (out / "summary.json").unlink(missing_ok=True)
    if result.scene.outputs.history:
        kept = h.iloc[::every]
        if kept.index[-1] != h.index[-1]:
            kept = pd.concat([kept, h.iloc[[-1]]])  # always keep the end
        paths["history"] = out / "history.csv"
        atomic_write_text(paths["history"], kept.to_csv(index=False, float_format="%.10g"))
    else:
        (out / "history.csv").unlink(missing_ok=True)
    atomic_write_text(paths["summary"], text)
    return paths
