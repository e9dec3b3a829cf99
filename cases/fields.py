"""Field plots for studies: resistance-centre and moment histories, and sigma_n around the shank.

``resistance_centre_from_tip`` is the point R on the axis with ``M = R x F`` (see
:func:`~cases.results.history_table`); R aft of the centre of mass gives a
restoring moment, ahead of it an overturning one.

The polar plot evaluates the DAFL law of the scene (the same
:class:`~fem_loads.dafl.DAFLLoads`, with its separation, guard, layers and
free-surface factor) on a ring of points of the exact surface at a chosen
station behind the tip, with the exact profile normals: the stress the law
gives there, not an interpolation of the mesh field.  The angle ``theta``
around the axis is measured from the windward side, the direction of the
transverse velocity of the axis point at that station; with no transverse
velocity (purely axial motion) it is measured from the body ``z`` axis.
"""

from __future__ import annotations

import os
from collections.abc import Sequence
from pathlib import Path

import numpy as np
import pandas as pd

from fem_loads import DAFLLoads, SurfaceQuadrature

from .results import save_figure
from .runner import PreparedProjectile

__all__ = ["ring_stress", "default_station", "plot_histories", "plot_polar"]


def default_station(prepared: PreparedProjectile) -> float:
    """A station on the shank (m behind the tip): one calibre behind the end of the nose,
    or the middle of the shank if that is shorter."""
    profile = prepared.profile
    return min(profile.nose_length + profile.diameter, 0.5 * (profile.nose_length + profile.length))


def ring_stress(evaluator, index: int, station: float, n: int = 360) -> tuple[np.ndarray, np.ndarray]:
    """``sigma_n`` (Pa) around the exact surface at ``station`` (m behind the tip) at row ``index``.

    Parameters
    ----------
    evaluator : FieldEvaluator
        The run's field (:class:`cases.render.FieldEvaluator`).
    index : int
        Trajectory row.
    station : float
        Distance behind the nose tip (m), ``0 < station < length``.
    n : int
        Points around the circumference.

    Returns
    -------
    theta : ndarray, shape (n,)
        Angle around the axis from the windward side (rad), see the module docstring.
    sigma_n : ndarray, shape (n,)
        Normal stress (Pa).
    """
    prepared = evaluator.prepared
    profile = prepared.profile
    if not (0.0 < station < profile.length):
        raise ValueError(f"station = {station}: must lie in (0, {profile.length:g}) m behind the tip")
    tr = evaluator.result.trajectory
    rotation = evaluator.rotations[index]
    velocity_body = tr.velocity[index] @ rotation
    omega = tr.angular_velocity[index]
    x = prepared.tip[0] - station
    axis_velocity = velocity_body + np.cross(omega, np.array([x, 0.0, 0.0]))
    transverse = axis_velocity[1:]
    norm = float(np.hypot(*transverse))
    if norm > 1e-9 * float(np.linalg.norm(axis_velocity)) and norm > 0:
        reference = transverse / norm
    else:
        reference = np.array([0.0, 1.0])  # body z
    theta = np.linspace(0.0, 2 * np.pi, n, endpoint=False)
    # e_rho = cos(theta) * reference + sin(theta) * (reference rotated by +90 deg about x)
    side = np.array([-reference[1], reference[0]])
    e_rho = np.outer(np.cos(theta), reference) + np.outer(np.sin(theta), side)
    radius = float(profile.radius_at(station))
    n_forward, n_radial = (float(v) for v in profile.outward_normal(station))
    points = np.column_stack([np.full(n, x), radius * e_rho])
    normals = np.column_stack([np.full(n, n_forward), n_radial * e_rho])
    loads = evaluator.loads
    ring = DAFLLoads(SurfaceQuadrature(points, normals, np.full(n, 1.0 / n)), loads.law,
                     loads.normal_velocity_guard, friction=loads.friction, separation=loads.separation,
                     free_surface=loads.free_surface)
    sigma, _ = ring.stress(tr.position[index], tr.velocity[index], rotation, omega)
    return theta, sigma


def plot_histories(history: pd.DataFrame, prepared: PreparedProjectile, path: str | os.PathLike,
                   instants: Sequence[tuple[str, int]] = ()) -> Path:
    """Resistance centre, pitch moment and attack angle against time, one PNG.

    The resistance centre is drawn only where it is defined (a transverse force); the centre of
    mass is the dashed line: the moment restores where R lies aft of it (below the line, since the
    axis points back from the tip).  The instants are marked by vertical lines.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    t = history["time"].to_numpy() * 1e3
    figure = Figure(figsize=(8, 8))
    FigureCanvasAgg(figure)
    centre_ax, moment_ax, angle_ax = figure.subplots(3, 1, sharex=True)
    centre = history["resistance_centre_from_tip"].to_numpy()
    length = prepared.profile.length
    shown = np.where((centre > -length) & (centre < 2 * length), centre, np.nan)
    centre_ax.plot(t, shown, color="tab:purple", lw=1.0, label="resistance centre R")
    centre_ax.axhline(prepared.mass.centre_from_tip, color="black", ls="--", lw=1.0, label="centre of mass")
    centre_ax.set_ylim(2 * length, -0.5 * length)
    centre_ax.set_ylabel("behind the tip (m)")
    centre_ax.set_title("resistance centre (R aft of the centre of mass: restoring moment)", fontsize=10)
    centre_ax.legend(fontsize=8, loc="lower right")
    moment = np.hypot(history["moment_y"].to_numpy(), history["moment_z"].to_numpy())
    moment_ax.plot(t, history["moment_y"].to_numpy() * 1e-3, color="tab:green", lw=1.0, label="pitch M_y (body)")
    moment_ax.plot(t, moment * 1e-3, color="0.5", lw=0.8, ls=":", label="|transverse moment|")
    moment_ax.set_ylabel("moment (kN m)")
    moment_ax.legend(fontsize=8)
    angle_ax.plot(t, history["attack_angle"], color="tab:red", lw=1.0)
    angle_ax.axhline(0.0, color="0.6", lw=0.6)
    angle_ax.set_ylabel("attack angle (deg)")
    angle_ax.set_xlabel("time (ms)")
    for label, row in instants:
        for ax in (centre_ax, moment_ax, angle_ax):
            ax.axvline(t[row], color="0.3", lw=0.7, ls="--")
        angle_ax.annotate(label or f"{t[row]:.1f} ms", (t[row], angle_ax.get_ylim()[1]), fontsize=7,
                          rotation=90, va="top", ha="right")
    for ax in (centre_ax, moment_ax, angle_ax):
        ax.grid(alpha=0.3)
    figure.tight_layout()
    return save_figure(figure, path, dpi=100)


def plot_polar(evaluator, instants: Sequence[tuple[str, int]], path: str | os.PathLike,
               station: float | None = None) -> Path:
    """Polar plot of ``sigma_n`` (MPa) around the shank at ``station`` (m behind the tip), one curve per instant.

    ``theta = 0`` is the windward side (see the module docstring).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    station = default_station(evaluator.prepared) if station is None else station
    figure = Figure(figsize=(6.5, 6.5))
    FigureCanvasAgg(figure)
    ax = figure.add_subplot(projection="polar")
    times = evaluator.result.trajectory.time
    for label, row in instants:
        theta, sigma = ring_stress(evaluator, row, station)
        closed = np.append(theta, theta[0])
        ax.plot(closed, np.append(sigma, sigma[0]) * 1e-6, lw=1.4,
                label=f"{label + ', ' if label else ''}t = {times[row] * 1e3:.2f} ms, "
                      f"attack {evaluator.history['attack_angle'].iloc[row]:+.2f} deg"
                      + ("" if sigma.max() > 0 else " (no stress at this station)"))
    ax.set_theta_zero_location("N")
    ax.set_title(f"sigma_n (MPa) around the surface {station:.3f} m behind the tip\n"
                 "(0 deg: windward side)", fontsize=10)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.06), ncol=1)
    figure.tight_layout()
    return save_figure(figure, path, dpi=100)
