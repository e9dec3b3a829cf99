"""Off-screen pyvista frames of a run's field: field images at chosen instants and an animated GIF.

VTK draws through EGL (``VTK_DEFAULT_OPENGL_WINDOW=vtkEGLRenderWindow``, set
here before VTK is imported unless the environment sets it), so no display or
X server is needed: the system libraries ``libegl1`` and ``libgl1-mesa-dri``
suffice.  Every plotter is closed in a ``finally`` block.  What the colours
mean is in :mod:`.field`.
"""

from __future__ import annotations

import io
import os
import time
from collections.abc import Iterable, Sequence
from pathlib import Path
from types import ModuleType
from typing import TYPE_CHECKING

os.environ.setdefault("VTK_DEFAULT_OPENGL_WINDOW", "vtkEGLRenderWindow")

import numpy as np  # noqa: E402

from ..run import atomic_write  # noqa: E402
from .field import FieldEvaluator, SurfaceField, frame_rows  # noqa: E402
from .panels import SidePanel  # noqa: E402
from .target_view import LAYER_SHADES, add_target  # noqa: E402

if TYPE_CHECKING:
    from pyvista import Camera, Plotter

__all__ = [
    "FrameRenderer",
    "render_snapshots",
    "render_animation",
    "png_bytes",
    "pyvista_off_screen",
    "colour_range",
    "field_ranges",
    "space_titles",
    "STRESS_CMAP",
    "N_COLOURS",
    "BACKGROUND",
]

STRESS_CMAP = "turbo"
N_COLOURS = 256
SOIL_LIGHT = (0.93, 0.88, 0.78)
# the target's layers behind the body, light enough for the stresses in front of them: soil's tan, then the others
LIGHT_SHADES = [SOIL_LIGHT] + [
    (r + 0.65 * (1 - r), g + 0.65 * (1 - g), b + 0.65 * (1 - b)) for r, g, b in LAYER_SHADES[1:]
]
HIDDEN_COLOUR = (0.55, 0.55, 0.55)  # facets the target cannot reach (fem_loads.exposure): no stress colour
BACKGROUND = "white"


def space_titles(plotter: Plotter) -> None:
    """Lift the colour bars' titles clear of their top labels."""
    for bar in plotter.scalar_bars.values():
        bar.SetVerticalTitleSeparation(12)


def pyvista_off_screen() -> ModuleType:
    """pyvista, set to draw off-screen (imported on first use: the ParaView writer needs no OpenGL)."""
    import pyvista as pv

    pv.OFF_SCREEN = True
    return pv


def colour_range(values: np.ndarray) -> tuple[float, float]:
    """Colour range of a field (MPa): its min and max (of the numbers: a hidden facet is NaN); a constant field
    gets a range of 1 MPa above it."""
    finite = values[np.isfinite(values)]
    lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 0.0)
    return (lo, hi) if hi > lo else (lo, lo + 1.0)


def field_ranges(evaluator: FieldEvaluator, rows: Iterable[int]) -> dict[str, tuple[float, float]]:
    """One colour range (MPa) per drawn field over the trajectory ``rows``: ``sigma_n`` (and ``tau`` with
    friction) from its min to its max over all of them (:func:`colour_range`), so pictures of those
    instants drawn with it compare."""
    low: dict[str, float] = {}
    high: dict[str, float] = {}
    for row in sorted({int(r) for r in rows}):  # one field at a time: a run's fields need not all fit in memory
        fld = evaluator.at(row)
        for name, values in (("sigma_n", fld.sigma_n), ("tau", fld.tau)):
            if values is not None:
                low[name] = min(low.get(name, np.inf), float(values.min()))
                high[name] = max(high.get(name, -np.inf), float(values.max()))
    return {name: colour_range(np.array([low[name], high[name]]) * 1e-6) for name in low}


def png_bytes(image: np.ndarray) -> bytes:
    """PNG encoding of an RGB image (Pillow)."""
    from PIL import Image

    buffer = io.BytesIO()
    Image.fromarray(image).save(buffer, format="PNG", optimize=True)
    return buffer.getvalue()


def _basis(direction: np.ndarray) -> np.ndarray:
    """A rotation whose first column is ``direction`` (unit)."""
    d = direction / np.linalg.norm(direction)
    helper = np.array([0.0, 1.0, 0.0]) if abs(d[1]) < 0.9 else np.array([1.0, 0.0, 0.0])
    b = np.cross(d, helper)
    b /= np.linalg.norm(b)
    return np.column_stack([d, b, np.cross(d, b)])


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
        Fixed colour range of ``sigma_n`` (MPa); by default each frame spans its own min..max.  Values
        outside it take the end colours, and the frame's caption gives the field's extreme.
    tau_clim : (float, float), optional
        The same for ``tau`` (MPa).
    """

    def __init__(
        self,
        evaluator: FieldEvaluator,
        size: tuple[int, int] = (1280, 640),
        *,
        side_panel: bool = True,
        lighting: bool = True,
        clim: tuple[float, float] | None = None,
        tau_clim: tuple[float, float] | None = None,
    ) -> None:
        pv = pyvista_off_screen()
        self.evaluator = evaluator
        width, height = size
        self.panel_width = int(round(0.3 * width)) if side_panel else 0
        self.view_size = (width - self.panel_width, height)
        self.fields = ["sigma_n", "tau"] if evaluator.friction else ["sigma_n"]
        self.fixed_clim = {"sigma_n": clim, "tau": tau_clim}
        self.plotter: Plotter | None = None
        self.panel = None
        self.last_field: SurfaceField | None = None
        self.last_clim: dict[str, tuple[float, float]] = {}
        try:
            self._build(pv, lighting)
            if side_panel:
                self.panel = SidePanel(evaluator, self.panel_width, height)
        except BaseException:
            self.close()
            raise

    def _build(self, pv: ModuleType, lighting: bool) -> None:
        ev = self.evaluator
        rows = len(self.fields)
        self.plotter = plotter = pv.Plotter(
            off_screen=True,
            window_size=self.view_size,
            shape=(rows, 1),
            border=False,
            lighting="light kit" if lighting else "none",
        )
        plotter.set_background(BACKGROUND)
        surface = ev.surface
        faces = np.hstack([np.full((len(surface.triangles), 1), 3), surface.triangles]).ravel()
        length = ev.length
        positions = ev.result.trajectory.position
        # the target seen from the side: its layers as a backdrop behind the body, and its faces
        x_lo, x_hi = positions[:, 0].min() - 5 * length, positions[:, 0].max() + 5 * length
        z_lo = min(positions[:, 2].min(), 0.0) - 5 * length
        z_hi = max(positions[:, 2].max(), 0.0) + 5 * length
        y_back = positions[:, 1].max() + 3 * length
        target = ev.result.scene.target
        path = pv.lines_from_points(positions) if len(positions) > 1 else None
        arrow = {
            "start": (0, 0, 0),
            "direction": (1, 0, 0),
            "scale": 1.0,
            "tip_length": 0.22,
            "tip_radius": 0.05,
            "shaft_radius": 0.015,
        }
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
                mesh,
                scalars=name,
                cmap=STRESS_CMAP,
                n_colors=N_COLOURS,
                clim=(0.0, 1.0),
                nan_color=HIDDEN_COLOUR,
                lighting=lighting,
                smooth_shading=False,
                show_scalar_bar=True,
                scalar_bar_args={
                    "title": unit,
                    "vertical": True,
                    "position_x": 0.86,
                    "position_y": 0.1,
                    "width": 0.06,
                    "height": 0.62,
                    "fmt": "%.4g",
                    "title_font_size": 14,
                    "label_font_size": 12,
                    "color": "black",
                    "n_labels": 6,
                },
            )
            self.meshes[name] = mesh
            add_target(plotter, pv, target, (x_lo, x_hi, z_lo, z_hi), y_back, 0.01 * length, LIGHT_SHADES)
            if path is not None:
                plotter.add_mesh(path, color=(0.45, 0.45, 0.45), line_width=1.0, lighting=False)
            plotter.add_mesh(self.arrow, color="black", lighting=lighting)
            self.texts[name] = plotter.add_text("", position="upper_edge", font_size=10, color="black")
            if row == len(self.fields) - 1:
                plotter.add_text(
                    "black arrow: velocity direction; shaded: the target's layers; grey: the centre of mass's path",
                    position="lower_left",
                    font_size=8,
                    color="black",
                )
            camera = plotter.camera
            camera.parallel_projection = True
        space_titles(plotter)
        self.scalar_bars = {name: self.actors[name].mapper.lookup_table for name in self.fields}

    def _update(self, index: int, label: str) -> dict[str, tuple[float, float]]:
        assert self.plotter is not None  # built in __init__, None only after close()
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
            assert values is not None  # tau is drawn only with friction, which gives it
            values_mpa = ev.cell_values(values) * 1e-6
            hidden = ev.cell_values(fld.hidden) if fld.hidden.size else np.zeros(len(values_mpa), dtype=bool)
            values_mpa[hidden] = np.nan  # drawn in HIDDEN_COLOUR: surface the target cannot reach
            mesh = self.meshes[name]
            mesh.points = points
            mesh.cell_data[name] = values_mpa
            clim = self.fixed_clim[name] or colour_range(values_mpa)
            self.actors[name].mapper.scalar_range = clim
            clims[name] = clim
            caption = fld.title(label) if row == 0 else "tangential stress tau (friction), against the slip"
            if hidden.any():
                caption += "   (grey: hidden by the body ahead)"
            if not values.any():
                caption += "   (no stress on the surface)"
            elif np.nanmin(values_mpa) < clim[0] or np.nanmax(values_mpa) > clim[1]:
                # a fixed range narrower than the field: its end colours would understate the extremes
                low, high = np.nanmin(values_mpa), np.nanmax(values_mpa)
                caption += f"   (field {low:.4g} .. {high:.4g} MPa, beyond the colour bar)"
            self.texts[name].SetText(2, caption)  # 2: upper edge
            self.plotter.subplot(row, 0)
            self._aim(self.plotter.camera, fld, tip)
        self.last_field = fld
        return clims

    def _aim(self, camera: Camera, fld: SurfaceField, tip: np.ndarray) -> None:
        """Side view from -Y (the paper's vertical plane), parallel projection, framing the body and the arrow.

        The body and the velocity arrow fill the left 84 % of the view (the colour bar takes the rest).
        """
        length = self.evaluator.length
        radius = 0.5 * self.evaluator.prepared.diameter
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
        assert self.plotter is not None  # built in __init__, None only after close()
        self.last_clim = self._update(index, label)
        self.plotter.render()
        screenshot = self.plotter.screenshot(None, return_img=True)
        view = np.asarray(screenshot)[:, :, :3]
        if self.panel is None:
            return view
        panel = self.panel.draw(index)
        return np.hstack([view, panel[: view.shape[0], :, :]])

    def to_pixels(self, points: np.ndarray, row: int = 0) -> np.ndarray:
        """Pixel (column, row from the top) of world points in the last frame, in panel ``row``'s view."""
        assert self.plotter is not None  # built in __init__, None only after close()
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
        low, high = self.scalar_bars[name].GetRange()
        return float(low), float(high)

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

    def __exit__(self, *exc: object) -> None:
        self.close()


def _file_label(label: str, time_s: float) -> str:
    """``nose_embedded`` for a named instant, ``t2.000ms`` for a chosen time."""
    return label.replace(" ", "_") if label else f"t{time_s * 1e3:.3f}ms"


def render_snapshots(
    evaluator: FieldEvaluator,
    out_dir: str | os.PathLike,
    instants: Sequence[tuple[str, int]],
    size: tuple[int, int] = (1280, 640),
    clim: tuple[float, float] | None = None,
    tau_clim: tuple[float, float] | None = None,
) -> list[Path]:
    """PNG images of the field at the given instants: ``field_<label>.png`` (``field_t<ms>ms.png`` unlabelled).

    Each image: the projectile in close-up coloured by ``sigma_n`` (and ``tau`` below it with
    friction), its colour bar in MPa (one range shared by all the images, so they compare), the velocity direction
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
    clim, tau_clim : (float, float), optional
        Colour range of ``sigma_n`` and ``tau`` (MPa); by default the min..max over all the
        ``instants`` (:func:`field_ranges`).

    Returns
    -------
    list of Path
        The written images, in the order of ``instants``.
    """
    out = Path(out_dir)
    paths = []
    if clim is None or (tau_clim is None and evaluator.friction):
        shared = field_ranges(evaluator, [row for _, row in instants])
        clim, tau_clim = clim or shared["sigma_n"], tau_clim or shared.get("tau")
    with FrameRenderer(evaluator, size, clim=clim, tau_clim=tau_clim) as renderer:
        for label, row in instants:
            image = renderer.render(row, label)
            path = out / f"field_{_file_label(label, evaluator.result.trajectory.time[row])}.png"
            atomic_write(path, png_bytes(image))
            paths.append(path)
    return paths


def render_animation(
    evaluator: FieldEvaluator,
    path: str | os.PathLike,
    frames: int = 60,
    fps: float = 12.0,
    size: tuple[int, int] = (960, 480),
    clim: str | tuple[float, float] = "frame",
    tau_clim: tuple[float, float] | None = None,
) -> dict:
    """An animated GIF (Pillow) of the run: the projectile along its path with its field and the histories.

    Parameters
    ----------
    frames : int
        Frames, evenly spaced in time.
    fps : float
        Frames per second of the GIF.
    clim : {"frame", "run"} or (float, float)
        Colour range of ``sigma_n``: each frame's own min..max (the pattern stays readable as the
        stress falls with speed), one range for the whole animation, the min..max over its frames
        (the magnitudes compare), or a given range in MPa (``penetrate render`` gives the range of
        its field images).
    tau_clim : (float, float), optional
        With a given ``clim``, the range of ``tau`` (MPa); by default the min..max over the frames.

    Returns
    -------
    dict
        ``path``, ``frames``, ``seconds`` (wall time), ``seconds_per_frame``, ``bytes``.
    """
    from PIL import Image

    if isinstance(clim, str) and clim not in ("frame", "run"):
        raise ValueError(f"clim = {clim!r}: must be 'frame', 'run' or a range (lo, hi) in MPa")
    start = time.perf_counter()
    rows = frame_rows(evaluator, frames)
    fixed, fixed_tau = (None, None) if isinstance(clim, str) else ((clim[0], clim[1]), tau_clim)
    if clim == "run" or (fixed_tau is None and fixed is not None and evaluator.friction):
        shared = field_ranges(evaluator, rows)
        fixed, fixed_tau = fixed or shared["sigma_n"], fixed_tau or shared.get("tau")
    images = []
    with FrameRenderer(evaluator, size, clim=fixed, tau_clim=fixed_tau) as renderer:
        for row in rows:
            frame = renderer.render(int(row))
            # an adaptive palette per frame keeps each in memory as one byte per pixel
            images.append(Image.fromarray(frame).quantize(colors=255, method=Image.Quantize.MEDIANCUT))
    buffer = io.BytesIO()
    images[0].save(
        buffer,
        format="GIF",
        save_all=True,
        append_images=images[1:],
        duration=int(round(1000 / fps)),
        loop=0,
        optimize=False,
    )
    data = buffer.getvalue()
    path = Path(path)
    atomic_write(path, data)
    seconds = time.perf_counter() - start
    return {
        "path": str(path),
        "frames": len(rows),
        "seconds": seconds,
        "seconds_per_frame": seconds / len(rows),
        "bytes": len(data),
    }
