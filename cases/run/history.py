"""A run's time history as a table, and what is read off it: the attack-angle peak and the convergence speed.

The columns are numpy arrays (:func:`history_columns`); :func:`history_table` puts them in a pandas
DataFrame for the studies and pictures.  A plain run needs no pandas (it costs 0.16 s to import).
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import TYPE_CHECKING

import numpy as np

from dynamics.convergence import crossing_speed_scalars
from dynamics.quaternion import rotation_matrices

from .runner import RunResult, tip_depths

if TYPE_CHECKING:
    import pandas as pd

__all__ = [
    "history_columns",
    "history_table",
    "history_csv",
    "attack_angle_peak",
    "convergence_speed",
    "HISTORY_UNITS",
    "ATTACK_ANGLE_SPEED_FRACTION",
    "CONVERGENCE_THRESHOLD",
    "RESISTANCE_CENTRE_FORCE_FRACTION",
]

ATTACK_ANGLE_SPEED_FRACTION = 0.1
CONVERGENCE_THRESHOLD = 0.1  # deg
# the transverse share of the force below which the resistance centre is not reported: once the attack
# angle has converged the transverse force is a residue (#3 at 1120 m/s: 0.4 % of the force, balanced
# about the centre of mass), and the paper's curves of the resistance centre stop there
RESISTANCE_CENTRE_FORCE_FRACTION = 1e-2

HISTORY_UNITS = {
    "time": "s",
    "position_x": "m",
    "position_y": "m",
    "position_z": "m",
    "velocity_x": "m/s",
    "velocity_y": "m/s",
    "velocity_z": "m/s",
    "speed": "m/s",
    "path_length": "m",
    "tip_depth": "m",
    "attitude_w": "1",
    "attitude_x": "1",
    "attitude_y": "1",
    "attitude_z": "1",
    "angular_velocity_x": "rad/s",
    "angular_velocity_y": "rad/s",
    "angular_velocity_z": "rad/s",
    "axis_angle": "deg",
    "velocity_angle": "deg",
    "attack_angle": "deg",
    "total_attack_angle": "deg",
    "force_x": "N",
    "force_y": "N",
    "force_z": "N",
    "moment_x": "N m",
    "moment_y": "N m",
    "moment_z": "N m",
    "resistance_centre_from_tip": "m",
}


def _plane_angle(vectors: np.ndarray) -> np.ndarray:
    """Angle (deg) in the vertical plane from the inward normal -Z towards +X, unwrapped along the run."""
    return np.degrees(np.unwrap(np.arctan2(vectors[:, 0], -vectors[:, 2])))


def history_table(result: RunResult) -> pd.DataFrame:
    """:func:`history_columns` as a pandas DataFrame."""
    import pandas as pd

    return pd.DataFrame(history_columns(result))


def history_columns(result: RunResult) -> dict[str, np.ndarray]:
    """One row per recorded step; the columns and their units are :data:`HISTORY_UNITS`.

    ``attack_angle`` is signed in the vertical plane (``axis_angle -
    velocity_angle``); ``total_attack_angle`` is the unsigned 3-D angle between
    the axis and the velocity.  ``resistance_centre_from_tip`` is the point R on
    the axis with ``M = R x F`` (least squares over the transverse force),
    measured back from the nose tip; it is reported only where the transverse
    force is at least :data:`RESISTANCE_CENTRE_FORCE_FRACTION` of the whole
    force (empty elsewhere): once the attack angle has converged the
    transverse force is a residue balanced about the centre of mass, and
    the curve stops, as the paper's does.
    """
    tr = result.trajectory
    rotation = rotation_matrices(tr.attitude)
    axis = rotation[:, :, 0]
    speed = np.linalg.norm(tr.velocity, axis=1)
    direction = tr.velocity / np.where(speed > 0, speed, 1.0)[:, None]
    total_attack = np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", axis, direction), -1.0, 1.0)))
    axis_angle = _plane_angle(axis)
    velocity_angle = _plane_angle(tr.velocity)
    attack = (axis_angle - velocity_angle + 180.0) % 360.0 - 180.0
    force_body = np.einsum("nji,nj->ni", rotation, tr.force)
    transverse2 = force_body[:, 1] ** 2 + force_body[:, 2] ** 2
    ahead = tr.moment[:, 2] * force_body[:, 1] - tr.moment[:, 1] * force_body[:, 2]
    defined = transverse2 >= (RESISTANCE_CENTRE_FORCE_FRACTION * np.linalg.norm(force_body, axis=1)) ** 2
    with np.errstate(divide="ignore", invalid="ignore"):
        centre = np.where(defined, result.prepared.mass.centre_from_tip - ahead / transverse2, np.nan)
    return {
        "time": tr.time,
        "position_x": tr.position[:, 0],
        "position_y": tr.position[:, 1],
        "position_z": tr.position[:, 2],
        "velocity_x": tr.velocity[:, 0],
        "velocity_y": tr.velocity[:, 1],
        "velocity_z": tr.velocity[:, 2],
        "speed": speed,
        "path_length": tr.path_length,
        "tip_depth": tip_depths(tr.position, rotation, result.prepared.tip, result.scene.target.face),
        "attitude_w": tr.attitude[:, 0],
        "attitude_x": tr.attitude[:, 1],
        "attitude_y": tr.attitude[:, 2],
        "attitude_z": tr.attitude[:, 3],
        "angular_velocity_x": tr.angular_velocity[:, 0],
        "angular_velocity_y": tr.angular_velocity[:, 1],
        "angular_velocity_z": tr.angular_velocity[:, 2],
        "axis_angle": axis_angle,
        "velocity_angle": velocity_angle,
        "attack_angle": attack,
        "total_attack_angle": total_attack,
        "force_x": tr.force[:, 0],
        "force_y": tr.force[:, 1],
        "force_z": tr.force[:, 2],
        "moment_x": tr.moment[:, 0],
        "moment_y": tr.moment[:, 1],
        "moment_z": tr.moment[:, 2],
        "resistance_centre_from_tip": centre,
    }


_NON_FINITE_CELL = re.compile(r"(?m)(?<![^,\n])-?(?:nan|inf)(?=,|$)")


def history_csv(table: pd.DataFrame | Mapping[str, np.ndarray], every: int = 1) -> bytes:
    """The table as CSV with ten significant digits, every ``every``-th row and always the last.

    Undefined cells (``resistance_centre_from_tip`` without a transverse force) are
    empty, never ``nan``.  Formatted as numpy's ``savetxt`` does, without its per-row overhead.
    """
    names = list(table.keys())
    values = np.column_stack([np.asarray(table[name], dtype=float) for name in names])
    kept = values[::every]
    if (len(values) - 1) % every:
        kept = np.vstack([kept, values[-1:]])  # always keep the end
    row = ",".join(["%.10g"] * len(names))  # numpy's savetxt formats each row so, one call a row
    text = "\n".join([",".join(names), *(row % tuple(values) for values in kept.tolist()), ""])
    return (text if np.isfinite(kept).all() else _NON_FINITE_CELL.sub("", text)).encode()


def attack_angle_peak(history: pd.DataFrame | Mapping[str, np.ndarray]) -> int:
    """Row (position) of the largest total attack angle while the speed is at least
    :data:`ATTACK_ANGLE_SPEED_FRACTION` of the impact speed (near rest the angle means nothing)."""
    speed = np.asarray(history["speed"])
    angle = np.asarray(history["total_attack_angle"])
    moving = np.flatnonzero(speed >= ATTACK_ANGLE_SPEED_FRACTION * speed[0])
    return int(moving[np.argmax(angle[moving])])


def convergence_speed(
    history: pd.DataFrame | Mapping[str, np.ndarray], threshold: float = CONVERGENCE_THRESHOLD
) -> float | None:
    """Speed (m/s) at which the attack angle, after its peak, first falls below ``threshold`` (deg).

    The peak is :func:`attack_angle_peak` (sought while the speed is at least 10 % of
    the impact speed); the crossing is interpolated linearly between the two steps.
    None if the angle never falls below the threshold.
    """
    speed = np.asarray(history["speed"])
    angle = np.asarray(history["total_attack_angle"])
    peak = attack_angle_peak(history)
    below = np.flatnonzero(angle[peak:] < threshold)
    if len(below) == 0:
        return None
    i = peak + int(below[0])
    if i == 0:
        return float(speed[i])
    return crossing_speed_scalars(float(angle[i - 1]), float(angle[i]), float(speed[i - 1]), float(speed[i]), threshold)
