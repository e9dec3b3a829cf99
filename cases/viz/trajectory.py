"""The whole path of a run in the target, off-screen: the projectile drawn to scale at several instants."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from ..run import atomic_write
from .field import FieldEvaluator, SurfaceField
from .frames import BACKGROUND, N_COLOURS, STRESS_CMAP, colour_range, png_bytes, pyvista_off_screen, space_titles
from .target_view import add_target

__all__ = ["render_trajectory", "trajectory_rows"]


def _label_anchor(fld: SurfaceField, positions: np.ndarray, length: float) -> tuple[np.ndarray, str]:
    """Where the time label of a body goes: 1 L off the path, across the velocity, away from the path's middle.

    Returns the anchor and the horizontal justification that keeps the text clear of the body.
    """
    v = fld.velocity[[0, 2]]
    across = np.array([-v[1], v[0]]) if np.linalg.norm(v) > 0 else np.array([1.0, 0.0])
    across /= np.linalg.norm(across)
    away = fld.position[[0, 2]] - positions[:, [0, 2]].mean(axis=0)
    if across @ away < 0 or (abs(across @ away) < 1e-9 and across[0] < 0):
        across = -across
    anchor = fld.position.copy()
    anchor[[0, 2]] += 1.0 * length * across
    anchor[1] -= 2 * length  # in front of the bodies and the path
    return anchor, ("right" if across[0] < -0.2 else "left" if across[0] > 0.2 else "center")


def trajectory_rows(evaluator: FieldEvaluator, count: int = 8) -> np.ndarray:
    """The trajectory rows of the bodies :func:`render_trajectory` draws: ``count`` instants evenly
    spaced in path length (fewer if some fall on the same step)."""
    s = evaluator.history["path_length"].to_numpy()
    return np.unique([int(np.argmin(np.abs(s - v))) for v in np.linspace(s[0], s[-1], count)])


def render_trajectory(
    evaluator: FieldEvaluator,
    path: str | os.PathLike,
    count: int = 8,
    size: tuple[int, int] = (1400, 700),
    clim: tuple[float, float] | None = None,
) -> Path:
    """The whole path in the target, seen from the side, with the projectile at ``count`` instants.

    The instants are evenly spaced in path length (:func:`trajectory_rows`).  The bodies are drawn
    to scale at their true positions and attitudes, coloured by ``sigma_n`` on one colour bar (MPa)
    spanning all of them, or ``clim``; each is labelled with its time and speed.  The target's layers are
    shaded regions behind them (tan the first), its faces brown lines.

    Parameters
    ----------
    evaluator : FieldEvaluator
        The run's field.
    path : path
        The PNG file to write.
    count : int
        Bodies drawn.
    size : (int, int)
        Width and height in pixels.
    clim : (float, float), optional
        Colour range of ``sigma_n`` (MPa); by default the min..max over the bodies drawn.

    Returns
    -------
    Path
        ``path``.
    """
    pv = pyvista_off_screen()
    ev = evaluator
    rows = trajectory_rows(ev, count)
    positions = ev.result.trajectory.position
    fields = [ev.at(int(r)) for r in rows]
    if clim is None:
        clim = colour_range(np.concatenate([f.sigma_n for f in fields]) * 1e-6)
    length = ev.length
    x_lo, x_hi = positions[:, 0].min() - 1.5 * length, positions[:, 0].max() + 1.5 * length
    z_lo = min(positions[:, 2].min(), 0.0) - 1.5 * length
    z_hi = max(positions[:, 2].max(), 0.0) + 2.5 * length
    # the scene in the left 86 % of the view, the colour bar right of it
    aspect = size[0] / size[1]
    usable = 0.86
    half_height = 0.5 * max(z_hi - z_lo, (x_hi - x_lo) / (usable * aspect))
    half_width = half_height * aspect
    centre = np.array([0.5 * (x_lo + x_hi) + (1 - usable) * half_width, 0.0, 0.5 * (z_lo + z_hi)])
    left, right = centre[0] - half_width - length, centre[0] + half_width + length
    bottom = centre[2] - half_height - length
    plotter = pv.Plotter(off_screen=True, window_size=size)
    try:
        plotter.set_background(BACKGROUND)
        behind = positions[:, 1].max() + 2 * length
        top = centre[2] + half_height + length
        add_target(plotter, pv, ev.result.scene.target, (left, right, bottom, top), behind, 0.01 * length)
        if len(positions) > 1:
            plotter.add_mesh(pv.lines_from_points(positions), color="black", line_width=2)
        faces = np.hstack([np.full((len(ev.surface.triangles), 1), 3), ev.surface.triangles]).ravel()
        for f in fields:
            body = pv.PolyData(ev.world_points(f.index), faces)
            body.cell_data["sigma_n"] = ev.cell_values(f.sigma_n) * 1e-6
            plotter.add_mesh(
                body,
                scalars="sigma_n",
                cmap=STRESS_CMAP,
                n_colors=N_COLOURS,
                clim=clim,
                scalar_bar_args={
                    "title": "sigma_n (MPa)",
                    "color": "black",
                    "fmt": "%.4g",
                    "vertical": True,
                    "position_x": 0.9,
                    "position_y": 0.15,
                    "width": 0.04,
                    "height": 0.6,
                    "title_font_size": 14,
                    "label_font_size": 12,
                },
            )
        placed = [_label_anchor(f, positions, length) for f in fields]
        for side in ("left", "center", "right"):
            chosen = [k for k, (_, j) in enumerate(placed) if j == side]
            if chosen:
                plotter.add_point_labels(
                    np.array([placed[k][0] for k in chosen]),
                    [f"{fields[k].time * 1e3:.1f} ms, {fields[k].speed:.0f} m/s" for k in chosen],
                    font_size=11,
                    point_size=1,
                    shape=None,
                    text_color="black",
                    show_points=False,
                    always_visible=True,
                    justification_horizontal=side,
                    justification_vertical="center",
                )
        space_titles(plotter)
        scene = ev.result.scene
        plotter.add_text(
            f"{scene.name or 'run'}: impact {scene.impact.speed:g} m/s, attack "
            f"{scene.impact.attack_angle:g} deg, oblique {scene.impact.oblique_angle:g} deg; "
            f"end: {ev.result.trajectory.end_reason}",
            position="upper_edge",
            font_size=10,
            color="black",
        )
        plotter.camera.parallel_projection = True
        plotter.camera.focal_point = centre
        plotter.camera.position = centre - np.array([0.0, 100 * (x_hi - x_lo), 0.0])
        plotter.camera.up = (0.0, 0.0, 1.0)
        plotter.camera.parallel_scale = half_height
        plotter.reset_camera_clipping_range()
        plotter.render()
        image = np.asarray(plotter.screenshot(None, return_img=True))[:, :, :3]
    finally:
        plotter.close()
        plotter.deep_clean()
    path = Path(path)
    atomic_write(path, png_bytes(image))
    return path
