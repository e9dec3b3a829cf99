"""Off-screen renderings of the DAFL resistance field: images, an animation and ParaView files.

What is drawn
-------------
The loads integrate the normal stress ``sigma_n`` at the surface quadrature
points (for the default ``quadrature_order = 2``, three points per facet of the
outer surface mesh).  A rendering gives every facet the area-weighted mean of
the stress at its own quadrature points,

    sigma_facet = sum_i sigma_i w_i / sum_i w_i,

so ``sum_facets sigma_facet * area_facet`` is exactly the ``sum_i sigma_i w_i``
the load integrates: the picture is the integrated field, spread evenly over
each facet, neither smoothed across facets nor re-evaluated elsewhere.  A facet
cut by the target surface shows the mean over its embedded and free parts.
With friction the tangential stress ``tau`` (its magnitude; it acts against
the local slip) is averaged the same way.  Second-order facets are drawn as
four flat triangles through their corner and edge nodes, each with the parent
facet's value.

The quadrature points of facet ``k`` are rows ``k * m .. k * m + m - 1`` of the
:class:`~fem_loads.quadrature.SurfaceQuadrature` (``m`` points per facet, in
the order of the mesh's ``outer`` triangles): that is how scikit-fem's facet
basis lays them out.  :func:`surface_mesh` checks the layout geometrically and
refuses a quadrature that does not follow it.

Frames
------
World frame ``X`` (right in the side views), ``Y`` (into the picture), ``Z``
up; the target is ``Z < 0``.  Body points are carried to the world by the
state's rotation and centre-of-mass position, so every picture and every
ParaView file has the projectile at its true position and attitude.

Off-screen
----------
VTK draws through EGL (``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow``, set
here before VTK is imported unless the environment sets it), so no display or
X server is needed: the system libraries ``libegl1`` and ``libgl1-mesa-dri``
suffice.  Every plotter is closed in a ``finally`` block.
"""

from __future__ import annotations

import io
import os
import time
import warnings
import xml.etree.ElementTree as ET
from collections.abc import Iterable, Sequence
from dataclasses import dataclass, field
from pathlib import Path

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402

from dynamics.quaternion import rotation_matrix  # noqa: E402
from fem_loads import DAFLLoads  # noqa: E402
from mesh import cached_mesh  # noqa: E402

from .results import atomic_write_bytes, atomic_write_text, attack_angle_peak, history_table  # noqa: E402
from .runner import PreparedProjectile, RunResult, scene_loads  # noqa: E402
from .schema import Numerics  # noqa: E402

__all__ = ["SurfaceMesh", "surface_mesh", "SurfaceField", "FieldEvaluator", "key_instants", "resolve_instants",
           "FrameRenderer", "render_snapshots", "render_trajectory", "render_animation", "write_paraview",
           "render_all", "png_bytes", "rss_bytes", "INSTANT_NAMES", "STRESS_CMAP", "PARAVIEW_INDEX",
           "TRAJECTORY_FIELDS"]

INSTANT_NAMES = ("embedded", "peak", "converged", "end")
INSTANT_LABELS = {"embedded": "nose embedded", "peak": "peak attack angle", "converged": "converged",
                  "end": "end"}
STRESS_CMAP = "turbo"
N_COLOURS = 256
PARAVIEW_INDEX = "run.pvd"
_SOIL = (0.80, 0.70, 0.52)
_SOIL_LIGHT = (0.93, 0.88, 0.78)
_BACKGROUND = "white"

# second-order triangle (corners 0-2, edge nodes 3 = 01, 4 = 12, 5 = 02) as four flat ones
_SPLIT6 = np.array([[0, 3, 5], [3, 1, 4], [5, 4, 2], [3, 4, 5]])


def _space_titles(plotter) -> None:
    """Lift the colour bars' titles clear of their top labels."""
    for bar in plotter.scalar_bars.values():
        bar.SetVerticalTitleSeparation(12)


def _pyvista():
    """pyvista, set to draw off-screen (imported on first use: the ParaView writer needs no OpenGL)."""
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


# ---------------------------------------------------------------------------------------------
# the surface and its field
# ---------------------------------------------------------------------------------------------


@dataclass(frozen=True)
class SurfaceMesh:
    """The outer surface as flat triangles in the body frame, about the centre of mass.

    Attributes
    ----------
    points : ndarray, shape (n_points, 3)
        Vertices (m), body frame (``x`` towards the nose), relative to the centre of mass.
    triangles : ndarray, shape (n_triangles, 3)
        Vertex indices of the drawn triangles (outward orientation).
    facet : ndarray, shape (n_triangles,)
        The mesh facet each drawn triangle belongs to (four per second-order facet).
    n_facets : int
        Number of facets of the outer surface mesh.
    points_per_facet : int
        Quadrature points per facet.
    """

    points: np.ndarray
    triangles: np.ndarray
    facet: np.ndarray
    n_facets: int
    points_per_facet: int


def surface_mesh(prepared: PreparedProjectile, numerics: Numerics) -> SurfaceMesh:
    """The drawn surface of a prepared projectile and the facet of every quadrature point.

    The mesh comes from the mesh cache (the same file the run used).

    Raises
    ------
    ValueError
        If the quadrature does not have the same number of points on every facet, or its
        points do not lie on their facets in facet order (see the module docstring).
    """
    mesh = cached_mesh(prepared.geometry, numerics.mesh_size, numerics.geometry_order)
    outer = np.asarray(mesh.outer, dtype=np.int64)
    n_facets = len(outer)
    n_points = len(prepared.quadrature)
    if n_facets == 0 or n_points % n_facets:
        raise ValueError(f"{n_points} quadrature points do not split evenly over {n_facets} facets")
    per = n_points // n_facets
    nodes = np.asarray(mesh.points, dtype=float) - prepared.mass.centre
    # layout check: the quadrature points of facet k lie on (near) facet k
    corners = nodes[outer[:, :3]]
    centroid = corners.mean(axis=1)
    edge = np.linalg.norm(corners - np.roll(corners, 1, axis=1), axis=2).max(axis=1)
    mean_point = prepared.quadrature.points.reshape(n_facets, per, 3).mean(axis=1)
    if np.any(np.linalg.norm(mean_point - centroid, axis=1) > 0.5 * edge):
        raise ValueError("the quadrature points are not laid out facet by facet in the order of the mesh")
    if outer.shape[1] == 6:
        triangles = outer[:, _SPLIT6].reshape(-1, 3)
        facet = np.repeat(np.arange(n_facets), len(_SPLIT6))
    else:
        triangles = outer[:, :3]
        facet = np.arange(n_facets)
    used, compact = np.unique(triangles, return_inverse=True)
    return SurfaceMesh(np.ascontiguousarray(nodes[used]), compact.reshape(-1, 3), facet, n_facets, per)


@dataclass(frozen=True)
class SurfaceField:
    """The resistance field on the surface at one recorded step.

    Attributes
    ----------
    index : int
        Row of the trajectory.
    time, speed : float
        s, m/s.
    attack_angle, total_attack_angle : float
        Signed in-plane and unsigned 3-D attack angle (deg).
    tip_depth : float
        Depth of the nose tip below the surface (m).
    position : ndarray, shape (3,)
        Centre of mass, world frame (m).
    velocity : ndarray, shape (3,)
        Centre-of-mass velocity, world frame (m/s).
    rotation : ndarray, shape (3, 3)
        Body-to-world rotation.
    sigma_n : ndarray, shape (n_facets,)
        Area-weighted facet mean of the normal stress (Pa).
    tau : ndarray, shape (n_facets,) or None
        Area-weighted facet mean of the tangential stress magnitude (Pa); None without friction.
    normal_velocity : ndarray, shape (n_facets,)
        Area-weighted facet mean of ``Vn`` (m/s).
    point_sigma_n : ndarray, shape (n_quadrature_points,)
        The normal stress at the quadrature points, as the loads use it (Pa).
    """

    index: int
    time: float
    speed: float
    attack_angle: float
    total_attack_angle: float
    tip_depth: float
    position: np.ndarray
    velocity: np.ndarray
    rotation: np.ndarray
    sigma_n: np.ndarray
    tau: np.ndarray | None
    normal_velocity: np.ndarray
    point_sigma_n: np.ndarray = field(repr=False)

    def title(self, label: str = "") -> str:
        """One line: instant, time, speed, attack angle and tip depth."""
        head = f"{label}   " if label else ""
        return (f"{head}t = {self.time * 1e3:.2f} ms   V = {self.speed:.0f} m/s   "
                f"attack {self.attack_angle:+.2f} deg   tip depth {self.tip_depth:.2f} m")


class FieldEvaluator:
    """Evaluates the resistance field of a finished run at any recorded step.

    Parameters
    ----------
    result : RunResult
        The run.
    history : DataFrame, optional
        Its :func:`~cases.results.history_table` (computed when not given).
    """

    def __init__(self, result: RunResult, history: pd.DataFrame | None = None) -> None:
        self.result = result
        self.history = history_table(result) if history is None else history
        self.prepared = result.prepared
        self.loads: DAFLLoads = scene_loads(result.scene, result.prepared)
        self.surface = surface_mesh(result.prepared, result.scene.numerics)
        q = result.prepared.quadrature
        per = self.surface.points_per_facet
        self._weights = q.weights.reshape(-1, per)
        self._areas = self._weights.sum(axis=1)
        tr = result.trajectory
        self.rotations = np.array([rotation_matrix(a) for a in tr.attitude])
        self.length = result.prepared.profile.length

    @property
    def friction(self) -> bool:
        """Whether the scene has a tangential stress."""
        return self.loads.friction is not None

    def __len__(self) -> int:
        return len(self.result.trajectory.time)

    def _facet_mean(self, values: np.ndarray) -> np.ndarray:
        return (values.reshape(self._weights.shape) * self._weights).sum(axis=1) / self._areas

    def at(self, index: int) -> SurfaceField:
        """The field at trajectory row ``index`` (negative counts from the end)."""
        tr = self.result.trajectory
        index = range(len(tr.time))[index]
        position, velocity = tr.position[index], tr.velocity[index]
        rotation, omega = self.rotations[index], tr.angular_velocity[index]
        sigma, vn = self.loads.stress(position, velocity, rotation, omega)
        tau = None
        if self.loads.friction is not None:
            tau = self._facet_mean(self._tangential(sigma, vn, velocity @ rotation, omega))
        row = self.history.iloc[index]
        return SurfaceField(index, float(tr.time[index]), float(row["speed"]), float(row["attack_angle"]),
                            float(row["total_attack_angle"]), float(row["tip_depth"]), position.copy(),
                            velocity.copy(), rotation.copy(), self._facet_mean(sigma), tau, self._facet_mean(vn),
                            sigma)

    def _tangential(self, sigma: np.ndarray, vn: np.ndarray, velocity_body: np.ndarray,
                    omega: np.ndarray) -> np.ndarray:
        """``tau`` at the quadrature points: the friction law where the point slips, else 0 (as the loads)."""
        q = self.prepared.quadrature
        u = velocity_body + np.cross(omega, q.points)
        slip = np.linalg.norm(u - vn[:, None] * q.normals, axis=1)
        moving = slip > 1e-12 * (float(np.linalg.norm(velocity_body)) + 1e-300)
        return np.where(moving, self.loads.friction.stress(sigma), 0.0)

    def world_points(self, index: int) -> np.ndarray:
        """Vertices of the drawn surface in the world frame at row ``index`` (m)."""
        tr = self.result.trajectory
        return self.surface.points @ self.rotations[index].T + tr.position[index]

    def tip(self, index: int) -> np.ndarray:
        """The nose tip in the world frame (m)."""
        return self.rotations[index] @ self.prepared.tip + self.result.trajectory.position[index]

    def cell_values(self, values: np.ndarray) -> np.ndarray:
        """Facet values repeated onto the drawn triangles."""
        return values[self.surface.facet]


def _nose_embedded_index(evaluator: FieldEvaluator) -> int | None:
    """First row at which every quadrature point of the nose is below the surface."""
    prepared = evaluator.prepared
    q = prepared.quadrature
    behind_tip = prepared.tip[0] - q.points[:, 0]
    nose = q.points[behind_tip <= prepared.profile.nose_length * (1 + 1e-9)]
    tr = evaluator.result.trajectory
    up = evaluator.rotations[:, 2, :]  # world Z of the body axes, one row per step
    for start in range(0, len(up), 512):
        highest = tr.position[start:start + 512, 2] + (up[start:start + 512] @ nose.T).max(axis=1)
        inside = np.flatnonzero(highest < 0.0)
        if len(inside):
            return start + int(inside[0])
    return None


def key_instants(evaluator: FieldEvaluator, threshold: float | None = None, unique: bool = True) -> dict[str, int]:
    """The rows of the default instants, in time order.

    ``embedded``: the first step with the whole nose below the surface (absent if it never is);
    ``peak``: the peak attack angle (:func:`~cases.results.attack_angle_peak`; absent if the
    attack angle stays below ``threshold``, as in purely axial motion); ``converged``: the first
    step after the peak with the total attack angle below ``threshold`` (the rule of
    :func:`~cases.studies.convergence_speed`; absent if it never falls below, or if the peak is
    absent: nothing converged); ``end``: the last step.

    Parameters
    ----------
    evaluator : FieldEvaluator
        The run.
    threshold : float, optional
        Convergence threshold (deg); :data:`~cases.studies.CONVERGENCE_THRESHOLD` by default.
    unique : bool
        Instants that fall on the same step keep only the first name.

    Returns
    -------
    dict
        Name to trajectory row, in time order.
    """
    from .studies import CONVERGENCE_THRESHOLD

    threshold = CONVERGENCE_THRESHOLD if threshold is None else threshold
    history = evaluator.history
    rows: dict[str, int] = {}
    embedded = _nose_embedded_index(evaluator)
    if embedded is not None:
        rows["embedded"] = embedded
    angle = history["total_attack_angle"].to_numpy()
    peak = attack_angle_peak(history)
    if angle[peak] >= threshold:
        rows["peak"] = peak
        below = np.flatnonzero(angle[peak:] < threshold)
        if len(below):
            rows["converged"] = peak + int(below[0])
    rows["end"] = len(history) - 1
    ordered = dict(sorted(rows.items(), key=lambda item: item[1]))
    if not unique:
        return ordered
    kept: dict[str, int] = {}
    for name, row in ordered.items():
        if row not in kept.values():
            kept[name] = row
    return kept


def resolve_instants(evaluator: FieldEvaluator, spec: Sequence[str] | None) -> list[tuple[str, int]]:
    """Labels and rows of instants given by name (:data:`INSTANT_NAMES`) or time in seconds.

    A time picks the nearest recorded step.  None gives the default instants.

    Raises
    ------
    ValueError
        For an unknown name, a time outside the run, or a named instant the run does not have.
    """
    if not spec:
        return [(INSTANT_LABELS[name], row) for name, row in key_instants(evaluator).items()]
    known = key_instants(evaluator, unique=False)
    known.setdefault("peak", attack_angle_peak(evaluator.history))  # asked for by name: even a small one
    times = evaluator.result.trajectory.time
    out = []
    for item in spec:
        text = str(item).strip()
        if text in INSTANT_NAMES:
            if text not in known:
                raise ValueError(f"--times {text}: this run has no such instant (it has {', '.join(known)})")
            out.append((INSTANT_LABELS[text], known[text]))
            continue
        try:
            t = float(text)
        except ValueError:
            raise ValueError(f"--times {text!r}: expected a time in seconds or one of {', '.join(INSTANT_NAMES)}")\
                from None
        if not (times[0] <= t <= times[-1]):
            raise ValueError(f"--times {text}: outside the run ({times[0]:g} .. {times[-1]:.6g} s)")
        out.append(("", int(np.argmin(np.abs(times - t)))))
    return out


def _frame_rows(evaluator: FieldEvaluator, frames: int | None) -> np.ndarray:
    """``frames`` rows evenly spaced in time (nearest recorded steps, first and last kept); None: every row."""
    times = evaluator.result.trajectory.time
    if frames is None or frames >= len(times):
        return np.arange(len(times))
    wanted = np.linspace(times[0], times[-1], frames)
    rows = np.clip(np.searchsorted(times, wanted), 0, len(times) - 1)
    lower = np.maximum(rows - 1, 0)
    rows = np.where(np.abs(times[lower] - wanted) < np.abs(times[rows] - wanted), lower, rows)
    return np.unique(rows)


def _range(values: np.ndarray) -> tuple[float, float]:
    """Colour range of a field (MPa): its min and max; a constant field gets a range of 1 MPa above it."""
    lo, hi = float(values.min()), float(values.max())
    return (lo, hi) if hi > lo else (lo, lo + 1.0)


def png_bytes(image: np.ndarray) -> bytes:
    """PNG encoding of an RGB image (Pillow)."""
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, format="PNG", optimize=True)
    return buffer.getvalue()


# ---------------------------------------------------------------------------------------------
# frames: one plotter and one matplotlib panel, reused
# ---------------------------------------------------------------------------------------------


def _basis(direction: np.ndarray) -> np.ndarray:
    """A rotation whose first column is ``direction`` (unit)."""
    d = direction / np.linalg.norm(direction)
    helper = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    b = np.cross(d, helper)
    b /= np.linalg.norm(b)
    return np.column_stack([d, b, np.cross(d, b)])


class _SidePanel:
    """Matplotlib panel beside the 3-D view: path in the target, speed and attack angle histories."""

    def __init__(self, evaluator: FieldEvaluator, width: int, height: int) -> None:
        from matplotlib.figure import Figure
        from matplotlib.backends.backend_agg import FigureCanvasAgg

        h = evaluator.history
        t = h["time"].to_numpy() * 1e3
        dpi = 100
        self.figure = Figure(figsize=(width / dpi, height / dpi), dpi=dpi)
        self.canvas = FigureCanvasAgg(self.figure)
        path_ax, speed_ax, angle_ax = self.figure.subplots(3, 1, gridspec_kw={"height_ratios": [1.4, 1, 1]})
        x, z = h["position_x"].to_numpy(), h["position_z"].to_numpy()
        span = max(np.ptp(x), np.ptp(z), evaluator.length)
        path_ax.axhspan(min(z.min(), 0.0) - 0.3 * span, 0.0, color=_SOIL, zorder=0)
        path_ax.axhline(0.0, color="saddlebrown", lw=1.5)
        path_ax.plot(x, z, color="0.35", lw=0.8)
        (self._axis_line,) = path_ax.plot([], [], color="crimson", lw=2.5, solid_capstyle="round")
        path_ax.set_xlim(x.min() - 0.15 * span, x.max() + 0.15 * span)
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


class FrameRenderer:
    """Renders frames of a run off-screen: the projectile in close-up with its field, beside the histories.

    One pyvista plotter and one matplotlib figure serve every frame (the meshes are
    updated in place), so rendering many frames neither re-creates OpenGL contexts
    nor grows memory.  Use as a context manager, or call :meth:`close`.

    Parameters
    ----------
    evaluator : FieldEvaluator
        The run's field.
    size : (int, int)
        Width and height of a frame (pixels), side panel included.
    side_panel : bool
        Draw the path, speed and attack-angle panel on the right.
    lighting : bool
        Shade the surface.  Off, every pixel of a facet has exactly its colour-map colour
        (used by the tests to read values back from pixels).
    clim : (float, float), optional
        Fixed colour range of ``sigma_n`` (MPa); by default each frame spans its own min..max.
    tau_clim : (float, float), optional
        The same for ``tau`` (MPa).
    """

    def __init__(self, evaluator: FieldEvaluator, size: tuple[int, int] = (1280, 640), *, side_panel: bool = True,
                 lighting: bool = True, clim: tuple[float, float] | None = None,
                 tau_clim: tuple[float, float] | None = None) -> None:
        pv = _pyvista()
        self.evaluator = evaluator
        width, height = size
        self.panel_width = int(round(0.3 * width)) if side_panel else 0
        self.view_size = (width - self.panel_width, height)
        self.fields = ["sigma_n", "tau"] if evaluator.friction else ["sigma_n"]
        self.fixed_clim = {"sigma_n": clim, "tau": tau_clim}
        self.plotter = None
        self.panel = None
        self.last_field: SurfaceField | None = None
        self.last_clim: dict[str, tuple[float, float]] = {}
        try:
            self._build(pv, lighting)
            if side_panel:
                self.panel = _SidePanel(evaluator, self.panel_width, height)
        except BaseException:
            self.close()
            raise

    def _build(self, pv, lighting: bool) -> None:
        ev = self.evaluator
        rows = len(self.fields)
        self.plotter = plotter = pv.Plotter(off_screen=True, window_size=self.view_size, shape=(rows, 1),
                                            border=False, lighting="light kit" if lighting else "none")
        plotter.set_background(_BACKGROUND)
        surface = ev.surface
        faces = np.hstack([np.full((len(surface.triangles), 1), 3), surface.triangles]).ravel()
        length = ev.length
        positions = ev.result.trajectory.position
        # the target seen from the side: a tan backdrop below Z = 0 behind the body, and the surface line
        x_lo, x_hi = positions[:, 0].min() - 5 * length, positions[:, 0].max() + 5 * length
        z_lo = min(positions[:, 2].min(), 0.0) - 5 * length
        y_back = positions[:, 1].max() + 3 * length
        soil = pv.Plane(center=(0.5 * (x_lo + x_hi), y_back, 0.5 * z_lo), direction=(0, -1, 0), i_size=-z_lo,
                        j_size=x_hi - x_lo)
        surface_line = pv.Line((x_lo, y_back - 0.01 * length, 0.0), (x_hi, y_back - 0.01 * length, 0.0))
        path = pv.lines_from_points(positions) if len(positions) > 1 else None
        arrow = {"start": (0, 0, 0), "direction": (1, 0, 0), "scale": 1.0, "tip_length": 0.22, "tip_radius": 0.05,
                 "shaft_radius": 0.015}
        self._arrow_template = np.asarray(pv.Arrow(**arrow).points)
        self.arrow = pv.Arrow(**arrow)
        self.meshes = {}
        self.actors = {}
        self.texts = {}
        for row, name in enumerate(self.fields):
            plotter.subplot(row, 0)
            mesh = pv.PolyData(surface.points.copy(), faces)
            mesh.cell_data[name] = np.zeros(len(surface.triangles))
            unit = "sigma_n (MPa)" if name == "sigma_n" else "tau (MPa)"
            self.actors[name] = plotter.add_mesh(
                mesh, scalars=name, cmap=STRESS_CMAP, n_colors=N_COLOURS, clim=(0.0, 1.0), lighting=lighting,
                smooth_shading=False, show_scalar_bar=True,
                scalar_bar_args={"title": unit, "vertical": True, "position_x": 0.86, "position_y": 0.1,
                                 "width": 0.06, "height": 0.62, "fmt": "%.4g", "title_font_size": 14,
                                 "label_font_size": 12, "color": "black", "n_labels": 6})
            self.meshes[name] = mesh
            plotter.add_mesh(soil, color=_SOIL_LIGHT, lighting=False)
            plotter.add_mesh(surface_line, color="saddlebrown", line_width=3, lighting=False)
            if path is not None:
                plotter.add_mesh(path, color=(0.45, 0.45, 0.45), line_width=1.0, lighting=False)
            plotter.add_mesh(self.arrow, color="black", lighting=lighting)
            self.texts[name] = plotter.add_text("", position="upper_edge", font_size=10, color="black")
            if row == len(self.fields) - 1:
                plotter.add_text("black arrow: velocity direction; tan: the target (Z < 0); grey line: path of"
                                 " the centre of mass", position="lower_left", font_size=8, color="black")
            camera = plotter.camera
            camera.parallel_projection = True
        _space_titles(plotter)
        self.scalar_bars = {name: self.actors[name].mapper.lookup_table for name in self.fields}

    # -- frames --------------------------------------------------------------------------------

    def _update(self, index: int, label: str) -> dict[str, tuple[float, float]]:
        ev = self.evaluator
        fld = ev.at(index)
        points = ev.surface.points @ fld.rotation.T + fld.position
        speed = float(np.linalg.norm(fld.velocity))
        tip = ev.tip(index)
        direction = fld.velocity / speed if speed > 0 else fld.rotation[:, 0]
        self.arrow.points = (self._arrow_template * (0.4 * ev.length)) @ _basis(direction).T + tip
        clims = {}
        for row, name in enumerate(self.fields):
            values = fld.sigma_n if name == "sigma_n" else fld.tau
            values_mpa = ev.cell_values(values) * 1e-6
            mesh = self.meshes[name]
            mesh.points = points
            mesh.cell_data[name] = values_mpa
            clim = self.fixed_clim[name] or _range(values_mpa)
            self.actors[name].mapper.scalar_range = clim
            clims[name] = clim
            caption = fld.title(label) if row == 0 else "tangential stress tau (friction), against the slip"
            if not values.any():
                caption += "   (no stress on the surface)"
            self.texts[name].SetText(2, caption)  # 2: upper edge
            self.plotter.subplot(row, 0)
            self._aim(self.plotter.camera, fld, tip)
        self.last_field = fld
        return clims

    def _aim(self, camera, fld: SurfaceField, tip: np.ndarray) -> None:
        """Side view from -Y (the paper's vertical plane), parallel projection, framing the body and the arrow.

        The body and the velocity arrow fill the left 84 % of the view (the colour bar takes the rest).
        """
        length = self.evaluator.length
        radius = 0.5 * self.evaluator.prepared.profile.diameter
        speed = float(np.linalg.norm(fld.velocity))
        ahead = fld.velocity / speed if speed > 0 else fld.rotation[:, 0]
        ends = np.array([tip, tip - length * fld.rotation[:, 0], tip + 0.4 * length * ahead])[:, [0, 2]]
        lo, hi = ends.min(axis=0) - 1.5 * radius, ends.max(axis=0) + 1.5 * radius
        w, h = self.view_size
        aspect = w / (h / len(self.fields))
        usable = 0.84
        half_height = 1.08 * max(0.5 * (hi[1] - lo[1]), 0.5 * (hi[0] - lo[0]) / (usable * aspect))
        camera.parallel_scale = half_height
        middle = 0.5 * (lo + hi)
        # the body's middle sits in the middle of the usable part: move the view's centre right of it
        centre = np.array([middle[0] + (1 - usable) * half_height * aspect, fld.position[1], middle[1]])
        camera.focal_point = centre
        camera.position = centre + np.array([0.0, -10 * length, 0.0])
        camera.up = (0.0, 0.0, 1.0)
        camera.clipping_range = (1 * length, 20 * length + self._depth_of_backdrop(fld))

    def _depth_of_backdrop(self, fld: SurfaceField) -> float:
        return float(self.evaluator.result.trajectory.position[:, 1].max() - fld.position[1])

    def render(self, index: int, label: str = "") -> np.ndarray:
        """The RGB frame (height x width x 3, uint8) of trajectory row ``index``, titled with ``label``."""
        self.last_clim = self._update(index, label)
        self.plotter.render()
        view = self.plotter.screenshot(None, return_img=True)
        view = np.asarray(view)[:, :, :3]
        if self.panel is None:
            return view
        panel = self.panel.draw(index)
        return np.hstack([view, panel[: view.shape[0], :, :]])

    def to_pixels(self, points: np.ndarray, row: int = 0) -> np.ndarray:
        """Pixel (column, row from the top) of world points in the last frame, in panel ``row``'s view."""
        renderer = self.plotter.renderers[row]
        out = []
        height = self.view_size[1]
        for p in np.atleast_2d(points):
            renderer.SetWorldPoint(*p, 1.0)
            renderer.WorldToDisplay()
            x, y, _ = renderer.GetDisplayPoint()
            out.append((x, height - 1 - y))
        return np.array(out)

    def scalar_bar_range(self, name: str = "sigma_n") -> tuple[float, float]:
        """The range (MPa) the colour bar of ``name`` shows in the last frame."""
        return tuple(float(v) for v in self.scalar_bars[name].GetRange())

    def close(self) -> None:
        """Release the OpenGL context and the figure."""
        if self.plotter is not None:
            self.plotter.close()
            self.plotter.deep_clean()
            self.plotter = None
        if self.panel is not None:
            self.panel.close()
            self.panel = None

    def __enter__(self) -> FrameRenderer:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


# ---------------------------------------------------------------------------------------------
# products
# ---------------------------------------------------------------------------------------------


def _file_label(label: str, time_s: float) -> str:
    """``nose_embedded`` for a named instant, ``t2.000ms`` for a chosen time."""
    return label.replace(" ", "_") if label else f"t{time_s * 1e3:.3f}ms"


def render_snapshots(evaluator: FieldEvaluator, out_dir: str | os.PathLike,
                     instants: Sequence[tuple[str, int]], size: tuple[int, int] = (1280, 640)) -> list[Path]:
    """PNG images of the field at the given instants: ``field_<label>.png`` (``field_t<ms>ms.png`` unlabelled).

    Each image: the projectile in close-up coloured by ``sigma_n`` (and ``tau`` below it with
    friction), its colour bar in MPa spanning the instant's min..max, the velocity direction
    (black arrow from the tip), the target (a tan backdrop below the surface line ``Z = 0``), the
    path of the centre of mass, a title (time, speed, attack angle, tip depth), and a side panel
    with the path in the target and the speed and attack-angle histories at that instant.

    Parameters
    ----------
    evaluator : FieldEvaluator
        The run's field.
    out_dir : path
        Folder to write into (made if missing).
    instants : sequence of (str, int)
        Label and trajectory row of each image (:func:`resolve_instants`).
    size : (int, int)
        Width and height in pixels.

    Returns
    -------
    list of Path
        The written images, in the order of ``instants``.
    """
    out = Path(out_dir)
    paths = []
    with FrameRenderer(evaluator, size) as renderer:
        for label, row in instants:
            image = renderer.render(row, label)
            path = out / f"field_{_file_label(label, evaluator.result.trajectory.time[row])}.png"
            atomic_write_bytes(path, png_bytes(image))
            paths.append(path)
    return paths


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


def render_trajectory(evaluator: FieldEvaluator, path: str | os.PathLike, count: int = 8,
                      size: tuple[int, int] = (1400, 700)) -> Path:
    """The whole path in the target, seen from the side, with the projectile at ``count`` instants.

    The instants are evenly spaced in path length.  The bodies are drawn to scale at their true
    positions and attitudes, coloured by ``sigma_n`` on one colour bar (MPa) spanning all of them;
    each is labelled with its time and speed.  The target is the tan region below the surface
    line ``Z = 0``.

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

    Returns
    -------
    Path
        ``path``.
    """
    pv = _pyvista()
    ev = evaluator
    h = ev.history
    s = h["path_length"].to_numpy()
    rows = np.unique([int(np.argmin(np.abs(s - v))) for v in np.linspace(s[0], s[-1], count)])
    positions = ev.result.trajectory.position
    fields = [ev.at(int(r)) for r in rows]
    values = np.concatenate([f.sigma_n for f in fields]) * 1e-6
    clim = _range(values)
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
        plotter.set_background(_BACKGROUND)
        behind = positions[:, 1].max() + 2 * length
        soil = pv.Plane(center=(0.5 * (left + right), behind, 0.5 * bottom), direction=(0, -1, 0),
                        i_size=-bottom, j_size=right - left)
        plotter.add_mesh(soil, color=_SOIL, lighting=False)
        plotter.add_mesh(pv.Line((left, behind - 0.01 * length, 0.0), (right, behind - 0.01 * length, 0.0)),
                         color="saddlebrown", line_width=3)
        if len(positions) > 1:
            plotter.add_mesh(pv.lines_from_points(positions), color="black", line_width=2)
        faces = np.hstack([np.full((len(ev.surface.triangles), 1), 3), ev.surface.triangles]).ravel()
        for f in fields:
            body = pv.PolyData(ev.world_points(f.index), faces)
            body.cell_data["sigma_n"] = ev.cell_values(f.sigma_n) * 1e-6
            plotter.add_mesh(body, scalars="sigma_n", cmap=STRESS_CMAP, n_colors=N_COLOURS, clim=clim,
                             scalar_bar_args={"title": "sigma_n (MPa)", "color": "black", "fmt": "%.4g",
                                              "vertical": True, "position_x": 0.9, "position_y": 0.15,
                                              "width": 0.04, "height": 0.6, "title_font_size": 14,
                                              "label_font_size": 12})
        placed = [_label_anchor(f, positions, length) for f in fields]
        for side in ("left", "center", "right"):
            chosen = [k for k, (_, j) in enumerate(placed) if j == side]
            if chosen:
                plotter.add_point_labels(np.array([placed[k][0] for k in chosen]),
                                         [f"{fields[k].time * 1e3:.1f} ms, {fields[k].speed:.0f} m/s" for k in chosen],
                                         font_size=11, point_size=1, shape=None, text_color="black",
                                         show_points=False, always_visible=True, justification_horizontal=side,
                                         justification_vertical="center")
        _space_titles(plotter)
        scene = ev.result.scene
        plotter.add_text(f"{scene.name or 'run'}: impact {scene.impact.speed:g} m/s, attack "
                         f"{scene.impact.attack_angle:g} deg, oblique {scene.impact.oblique_angle:g} deg; "
                         f"end: {ev.result.trajectory.end_reason}", position="upper_edge", font_size=10,
                         color="black")
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
    atomic_write_bytes(path, png_bytes(image))
    return path


def render_animation(evaluator: FieldEvaluator, path: str | os.PathLike, frames: int = 60, fps: float = 12.0,
                     size: tuple[int, int] = (960, 480), clim: str = "frame") -> dict:
    """An animated GIF (Pillow) of the run: the projectile along its path with its field and the histories.

    Parameters
    ----------
    frames : int
        Frames, evenly spaced in time.
    fps : float
        Frames per second of the GIF.
    clim : {"frame", "run"}
        Colour range of ``sigma_n``: each frame's own min..max (the pattern stays readable as the
        stress falls with speed) or one range for the whole run (the magnitudes compare).

    Returns
    -------
    dict
        ``path``, ``frames``, ``seconds`` (wall time), ``seconds_per_frame``, ``bytes``.
    """
    from PIL import Image

    if clim not in ("frame", "run"):
        raise ValueError(f"clim = {clim!r}: must be 'frame' or 'run'")
    start = time.perf_counter()
    rows = _frame_rows(evaluator, frames)
    fixed = fixed_tau = None
    if clim == "run":
        fields = [evaluator.at(int(r)) for r in rows]
        fixed = _range(np.concatenate([f.sigma_n for f in fields]) * 1e-6)
        if evaluator.friction:
            fixed_tau = _range(np.concatenate([f.tau for f in fields]) * 1e-6)
    images = []
    with FrameRenderer(evaluator, size, clim=fixed, tau_clim=fixed_tau) as renderer:
        for row in rows:
            frame = renderer.render(int(row))
            # an adaptive palette per frame keeps each in memory as one byte per pixel
            images.append(Image.fromarray(frame).quantize(colors=255, method=Image.Quantize.MEDIANCUT))
    buffer = io.BytesIO()
    images[0].save(buffer, format="GIF", save_all=True, append_images=images[1:],
                   duration=int(round(1000 / fps)), loop=0, optimize=False)
    data = buffer.getvalue()
    path = Path(path)
    atomic_write_bytes(path, data)
    seconds = time.perf_counter() - start
    return {"path": str(path), "frames": len(rows), "seconds": seconds, "seconds_per_frame": seconds / len(rows),
            "bytes": len(data)}


# ---------------------------------------------------------------------------------------------
# ParaView
# ---------------------------------------------------------------------------------------------


def _write_meshio(path: Path, mesh) -> None:
    """meshio write through a temporary file renamed into place."""
    import meshio

    tmp = path.with_name(f".{path.stem}.tmp{path.suffix}")
    try:
        meshio.write(tmp, mesh, binary=True)
        os.replace(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


TRAJECTORY_FIELDS = {"time": "s", "speed": "m/s", "attack_angle": "deg", "total_attack_angle": "deg",
                     "tip_depth": "m", "path_length": "m", "resistance_centre_from_tip": "m"}


def write_paraview(evaluator: FieldEvaluator, out_dir: str | os.PathLike, steps: int | None = 100) -> dict:
    """ParaView files of the run: the surface field over time and the path.

    Writes, in ``out_dir``:

    * ``surface/surface_NNNNN.vtu``: the drawn surface at its true position and attitude (world
      frame, m) with cell data ``sigma_n`` (Pa), ``normal_velocity`` (m/s) and, with friction,
      ``tau`` (Pa), one file per written step;
    * ``trajectory.vtu``: the centre-of-mass path as line segments with point data
      :data:`TRAJECTORY_FIELDS` (every recorded step);
    * ``run.pvd``: the index: each step's surface (part 0) and the path (part 1) at its time, so
      opening this one file in ParaView plays the run.

    Parameters
    ----------
    steps : int or None
        Number of steps written, evenly spaced in time; None writes every recorded step.

    Returns
    -------
    dict
        ``index`` (path of run.pvd), ``surfaces`` (list of paths), ``trajectory``, ``times``, ``rows``.
    """
    import meshio

    out = Path(out_dir)
    (out / "surface").mkdir(parents=True, exist_ok=True)
    ev = evaluator
    rows = _frame_rows(ev, steps)
    cells = [("triangle", ev.surface.triangles.astype(np.int64))]
    surfaces, times = [], []
    for n, row in enumerate(rows):
        fld = ev.at(int(row))
        data = {"sigma_n": [ev.cell_values(fld.sigma_n)], "normal_velocity": [ev.cell_values(fld.normal_velocity)]}
        if fld.tau is not None:
            data["tau"] = [ev.cell_values(fld.tau)]
        path = out / "surface" / f"surface_{n:05d}.vtu"
        _write_meshio(path, meshio.Mesh(ev.world_points(int(row)), cells, cell_data=data))
        surfaces.append(path)
        times.append(fld.time)
    positions = ev.result.trajectory.position
    n_points = len(positions)
    segments = np.column_stack([np.arange(n_points - 1), np.arange(1, n_points)]) if n_points > 1 \
        else np.zeros((0, 2), dtype=np.int64)
    point_data = {name: ev.history[name].to_numpy(dtype=float) for name in TRAJECTORY_FIELDS}
    trajectory = out / "trajectory.vtu"
    _write_meshio(trajectory, meshio.Mesh(positions, [("line", segments)], point_data=point_data))
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    collection = ET.SubElement(root, "Collection")
    for path, t in zip(surfaces, times):
        ET.SubElement(collection, "DataSet", timestep=repr(float(t)), group="", part="0",
                      file=path.relative_to(out).as_posix())
        ET.SubElement(collection, "DataSet", timestep=repr(float(t)), group="", part="1", file=trajectory.name)
    ET.indent(root)
    index = out / PARAVIEW_INDEX
    atomic_write_text(index, '<?xml version="1.0"?>\n' + ET.tostring(root, encoding="unicode") + "\n")
    return {"index": index, "surfaces": surfaces, "trajectory": trajectory, "times": times,
            "rows": [int(r) for r in rows]}


def render_all(result: RunResult, out_dir: str | os.PathLike, times: Iterable[str] | None = None, *,
               animation: bool = False, paraview: bool = False, frames: int = 60, steps: int | None = 100,
               station: float | None = None, size: tuple[int, int] = (1280, 640)) -> dict:
    """Everything ``penetrate render`` writes.

    Parameters
    ----------
    result : RunResult
        The run.
    out_dir : path
        Folder to write into.
    times : iterable of str, optional
        Instants by name or time in seconds (:func:`resolve_instants`); the default instants if None.
    animation, paraview : bool
        Also write ``animation.gif`` and ``paraview/run.pvd`` with its files.
    frames : int
        Frames of the animation.
    steps : int or None
        Steps of the ParaView output (None: every recorded step).
    station : float, optional
        Distance behind the tip (m) of the polar plot's ring.
    size : (int, int)
        Size of the field images in pixels.

    Returns
    -------
    dict
        ``instants`` (label, row, time), ``files`` (written paths), ``seconds`` (wall time of each
        part and ``total``) and, with ``paraview``, ``paraview_steps``.
    """
    from .fields import plot_histories, plot_polar

    out = Path(out_dir)
    record: dict = {"files": [], "seconds": {}}
    start = time.perf_counter()
    evaluator = FieldEvaluator(result)
    instants = resolve_instants(evaluator, list(times) if times else None)
    record["instants"] = [{"label": label, "row": row, "time": float(evaluator.result.trajectory.time[row])}
                          for label, row in instants]
    t0 = time.perf_counter()
    record["files"] += [str(p) for p in render_snapshots(evaluator, out, instants, size)]
    record["seconds"]["snapshots"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    record["files"].append(str(render_trajectory(evaluator, out / "trajectory.png")))
    record["seconds"]["trajectory"] = time.perf_counter() - t0
    t0 = time.perf_counter()
    record["files"].append(str(plot_histories(evaluator.history, evaluator.prepared, out / "resistance_centre.png",
                                              instants)))
    record["files"].append(str(plot_polar(evaluator, instants, out / "polar.png", station)))
    record["seconds"]["field_plots"] = time.perf_counter() - t0
    if animation:
        movie = render_animation(evaluator, out / "animation.gif", frames)
        record["files"].append(movie["path"])
        record["seconds"]["animation"] = movie["seconds"]
    if paraview:
        t0 = time.perf_counter()
        written = write_paraview(evaluator, out / "paraview", steps)
        record["files"].append(str(written["index"]))
        record["paraview_steps"] = len(written["surfaces"])
        record["seconds"]["paraview"] = time.perf_counter() - t0
    record["seconds"]["total"] = time.perf_counter() - start
    return record


def rss_bytes() -> int:
    """Resident memory of this process (bytes), from ``/proc/self/statm`` (Linux)."""
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")

