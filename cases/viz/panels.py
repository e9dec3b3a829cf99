"""Matplotlib panels of a run's field: the side panel of the frames, resistance-centre and moment
histories, and ``sigma_n`` around the shank.

``resistance_centre_from_tip`` is the point R on the axis with ``M = R x F`` (see
:func:`~cases.run.history_table`); R aft of the centre of mass gives a
restoring moment, ahead of it an overturning one.

The polar plot evaluates the DAFL law of the scene (the run's own
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
import warnings
from collections.abc import Sequence
from pathlib import Path
from typing import TYPE_CHECKING, cast

import numpy as np
import pandas as pd

from fem_loads import DAFLLoads, SurfaceQuadrature

from ..run import PreparedProjectile
from ..scene import InputError
from .field import FieldEvaluator
from .figures import legend_outside, new_figure, save_figure
from .target_view import LAYER_SHADES, target_view

if TYPE_CHECKING:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.projections.polar import PolarAxes

__all__ = ["SidePanel", "ring_stress", "default_station", "plot_histories", "plot_polar", "SOIL"]

SOIL = LAYER_SHADES[0]


class SidePanel:
    """Matplotlib panel beside the 3-D view: path in the target, speed and attack angle histories."""

    def __init__(self, evaluator: FieldEvaluator, width: int, height: int) -> None:
        h = evaluator.history
        t = h["time"].to_numpy() * 1e3
        dpi = 100
        self.figure = new_figure((width / dpi, height / dpi), dpi)
        # new_figure draws on the Agg canvas, whose blitting and pixel buffer the frames use
        self.canvas = cast("FigureCanvasAgg", self.figure.canvas)
        path_ax, speed_ax, angle_ax = self.figure.subplots(3, 1, gridspec_kw={"height_ratios": [1.4, 1, 1]})
        x, z = h["position_x"].to_numpy(), h["position_z"].to_numpy()
        span = max(np.ptp(x), np.ptp(z), evaluator.length)
        box = (x.min() - 0.3 * span, x.max() + 0.3 * span, min(z.min(), 0.0) - 0.3 * span, 0.3 * span)
        view = target_view(evaluator.result.scene.target, box)
        for band, shade in zip(view.bands, view.shades):
            path_ax.fill(band[:, 0], band[:, 1], color=shade, zorder=0, lw=0)
        for face in view.faces:
            path_ax.plot(face[:, 0], face[:, 1], color="saddlebrown", lw=1.5)
        path_ax.plot(x, z, color="0.35", lw=0.8)
        (self._axis_line,) = path_ax.plot([], [], color="crimson", lw=2.5, solid_capstyle="round")
        path_ax.set_xlim(x.min() - 0.15 * span, x.max() + 0.15 * span)  # the faces' long lines cut at the view
        path_ax.set_ylim(min(z.min(), 0.0) - 0.1 * span, 0.15 * span)
        path_ax.set_aspect("equal", adjustable="box")
        path_ax.set_xlabel("X (m)", fontsize=8)
        path_ax.set_ylabel("Z (m)", fontsize=8)
        path_ax.set_title("path of the centre of mass in the target", fontsize=8)
        speed_ax.plot(t, h["speed"], color="tab:blue", lw=1.2)
        speed_ax.set_ylabel("speed (m/s)", fontsize=8)
        angle_ax.plot(t, h["attack_angle"], color="tab:red", lw=1.2)
        angle_ax.axhline(0.0, color="0.6", lw=0.6)
        angle_ax.set_ylabel("attack angle (deg)", fontsize=8)
        angle_ax.set_xlabel("time (ms)", fontsize=8)
        self._cursors = [ax.axvline(t[0], color="0.2", lw=0.8, ls="--") for ax in (speed_ax, angle_ax)]
        (self._speed_dot,) = speed_ax.plot([], [], "o", color="tab:blue", ms=5)
        (self._angle_dot,) = angle_ax.plot([], [], "o", color="tab:red", ms=5)
        for ax in (path_ax, speed_ax, angle_ax):
            ax.tick_params(labelsize=7)
            ax.grid(alpha=0.3)
        with warnings.catch_warnings():  # a small panel cannot fit every label: draw it anyway
            warnings.simplefilter("ignore", UserWarning)
            self.figure.tight_layout(pad=0.6)
        self._evaluator = evaluator
        self._t = t
        # blitting: the axes, ticks and histories are drawn once; a frame redraws only the markers
        self._moving = [self._axis_line, *self._cursors, self._speed_dot, self._angle_dot]
        for artist in self._moving:
            artist.set_animated(True)
        self.canvas.draw()
        self._background = self.canvas.copy_from_bbox(self.figure.bbox)

    def draw(self, index: int) -> np.ndarray:
        ev = self._evaluator
        h = ev.history
        tip = ev.tip(index)
        tail = tip - ev.rotations[index][:, 0] * ev.length
        self._axis_line.set_data([tip[0], tail[0]], [tip[2], tail[2]])
        t = self._t[index]
        for cursor in self._cursors:
            cursor.set_xdata([t, t])
        self._speed_dot.set_data([t], [h["speed"].iloc[index]])
        self._angle_dot.set_data([t], [h["attack_angle"].iloc[index]])
        self.canvas.restore_region(self._background)
        for artist in self._moving:
            artist.axes.draw_artist(artist)
        return np.asarray(self.canvas.buffer_rgba())[:, :, :3].copy()

    def close(self) -> None:
        self.figure.clear()


def default_station(prepared: PreparedProjectile) -> float:
    """A station on the shank (m behind the tip): one calibre behind the end of the nose,
    or the middle of the shank if that is shorter."""
    return min(prepared.nose_length + prepared.diameter, 0.5 * (prepared.nose_length + prepared.length))


def ring_stress(evaluator: FieldEvaluator, index: int, station: float, n: int = 360) -> tuple[np.ndarray, np.ndarray]:
    """``sigma_n`` (Pa) around the exact surface at ``station`` (m behind the tip) at row ``index``.

    Parameters
    ----------
    evaluator : FieldEvaluator
        The run's field.
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
    if not (0.0 < station < prepared.length):
        raise InputError(f"station = {station}: must lie in (0, {prepared.length:g}) m behind the tip")
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
    if prepared.outline is not None:  # a body from a file: no profile, its own surface points at the station
        return _ring_of_points(evaluator, index, x, reference, side)
    profile = prepared.profile
    radius = float(profile.radius_at(station))
    n_forward, n_radial = (float(v) for v in profile.outward_normal(station))
    points = np.column_stack([np.full(n, x), radius * e_rho])
    normals = np.column_stack([np.full(n, n_forward), n_radial * e_rho])
    loads = evaluator.loads
    ring = DAFLLoads(
        SurfaceQuadrature(points, normals, np.full(n, 1.0 / n)),
        loads.law,
        loads.normal_velocity_guard,
        friction=loads.friction,
        separation=loads.separation,
        free_surface=loads.free_surface,
    )
    return theta, ring.surface_stress(tr.position[index], tr.velocity[index], rotation, omega).sigma_n


def _ring_of_points(
    evaluator: FieldEvaluator, index: int, x: float, reference: np.ndarray, side: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    """``sigma_n`` at the body's own quadrature points within half an element of the body-frame ``x``, by
    their angle from the windward side: a body of any shape, read from a file, has no exact ring."""
    prepared = evaluator.prepared
    q = prepared.quadrature
    half = 0.5 * evaluator.result.scene.numerics.mesh_size
    band = np.flatnonzero(np.abs(q.points[:, 0] - x) <= half)  # x and the points: from the centre of mass
    tr = evaluator.result.trajectory
    stress = evaluator.loads.surface_stress(
        tr.position[index], tr.velocity[index], evaluator.rotations[index], tr.angular_velocity[index]
    )
    lateral = q.points[band, 1:] - prepared.tip[1:]  # from the axis through the tip
    theta = np.mod(np.arctan2(lateral @ side, lateral @ reference), 2 * np.pi)
    order = np.argsort(theta)
    return theta[order], stress.sigma_n[band][order]


def plot_histories(
    history: pd.DataFrame,
    prepared: PreparedProjectile,
    path: str | os.PathLike,
    instants: Sequence[tuple[str, int]] = (),
) -> Path:
    """Resistance centre, pitch moment and attack angle against time, one PNG.

    The resistance centre is drawn only where it is defined (a transverse force); the centre of
    mass is the dashed line: the moment restores where R lies aft of it (below the line, since the
    axis points back from the tip).  The instants are marked by vertical lines.
    """
    t = history["time"].to_numpy() * 1e3
    figure = new_figure((9.5, 8))
    centre_ax, moment_ax, angle_ax = figure.subplots(3, 1, sharex=True)
    centre = history["resistance_centre_from_tip"].to_numpy()
    length = prepared.length
    shown = np.where((centre > -length) & (centre < 2 * length), centre, np.nan)
    centre_ax.plot(t, shown, color="tab:purple", lw=1.0, label="resistance centre R")
    centre_ax.axhline(prepared.mass.centre_from_tip, color="black", ls="--", lw=1.0, label="centre of mass")
    centre_ax.set_ylim(2 * length, -0.5 * length)
    centre_ax.set_ylabel("behind the tip (m)")
    centre_ax.set_title("resistance centre (R aft of the centre of mass: restoring moment)", fontsize=10)
    legend_outside(centre_ax)
    moment = np.hypot(history["moment_y"].to_numpy(), history["moment_z"].to_numpy())
    moment_ax.plot(t, history["moment_y"].to_numpy() * 1e-3, color="tab:green", lw=1.0, label="pitch M_y (body)")
    moment_ax.plot(t, moment * 1e-3, color="0.5", lw=0.8, ls=":", label="|transverse moment|")
    moment_ax.set_ylabel("moment (kN m)")
    legend_outside(moment_ax)
    angle_ax.plot(t, history["attack_angle"], color="tab:red", lw=1.0)
    angle_ax.axhline(0.0, color="0.6", lw=0.6)
    angle_ax.set_ylabel("attack angle (deg)")
    angle_ax.set_xlabel("time (ms)")
    for label, row in instants:
        for ax in (centre_ax, moment_ax, angle_ax):
            ax.axvline(t[row], color="0.3", lw=0.7, ls="--")
        angle_ax.annotate(
            label or f"{t[row]:.1f} ms", (t[row], angle_ax.get_ylim()[1]), fontsize=7, rotation=90, va="top", ha="right"
        )
    for ax in (centre_ax, moment_ax, angle_ax):
        ax.grid(alpha=0.3)
    figure.tight_layout()
    return save_figure(figure, path, dpi=100)


def plot_polar(
    evaluator: FieldEvaluator,
    instants: Sequence[tuple[str, int]],
    path: str | os.PathLike,
    station: float | None = None,
) -> Path:
    """Polar plot of ``sigma_n`` (MPa) around the shank at ``station`` (m behind the tip), one curve per instant.

    ``theta = 0`` is the windward side (see the module docstring).
    """
    from matplotlib.ticker import FuncFormatter

    station = default_station(evaluator.prepared) if station is None else station
    figure = new_figure((6.5, 6.5))
    ax = cast("PolarAxes", figure.add_subplot(projection="polar"))
    times = evaluator.result.trajectory.time
    for label, row in instants:
        theta, sigma = ring_stress(evaluator, row, station)
        closed = np.append(theta, theta[0])
        ax.plot(
            closed,
            np.append(sigma, sigma[0]) * 1e-6,
            lw=1.4,
            label=f"{label + ', ' if label else ''}t = {times[row] * 1e3:.2f} ms, "
            f"attack {evaluator.history['attack_angle'].iloc[row]:+.2f} deg"
            + ("" if sigma.max() > 0 else " (no stress at this station)"),
        )
    ax.set_theta_zero_location("N")
    # a polar plot has no radial axis label to carry the unit: each radial tick carries it
    ax.yaxis.set_major_formatter(FuncFormatter(lambda value, _: f"{value:g} MPa"))
    ax.set_title(
        f"sigma_n (MPa) around the surface {station:.3f} m behind the tip\n(0 deg: windward side)", fontsize=10
    )
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.06), ncol=1)
    figure.tight_layout()
    return save_figure(figure, path, dpi=100)
