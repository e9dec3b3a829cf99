"""The target seen from the side (the ``XZ`` plane): its material layers as polygons and its faces as lines, for
every picture that draws the target (the trajectory render, the frames' backdrop, the side panel)."""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import numpy as np

from ..scene import Target

if TYPE_CHECKING:
    from types import ModuleType

    from pyvista import Plotter

__all__ = ["TargetView", "target_view", "add_target", "LAYER_SHADES"]

#: the shades of successive material layers (RGB), the first the tan of soil
LAYER_SHADES = ((0.80, 0.70, 0.52), (0.62, 0.62, 0.62), (0.70, 0.58, 0.42), (0.55, 0.55, 0.60))


class TargetView:
    """``bands``: each material layer's polygon (``(k, 2)`` arrays of ``(X, Z)``, m) inside the box, with its
    ``shades`` (one per law, in the order the laws first appear); ``faces``: each face of the target (front,
    interfaces, rear) as a segment ``(2, 2)`` across it."""

    def __init__(self, bands: list[np.ndarray], shades: list[tuple[float, float, float]], faces: list[np.ndarray]):
        self.bands, self.shades, self.faces = bands, shades, faces


def _clip(polygon: np.ndarray, normal: np.ndarray, limit: float) -> np.ndarray:
    """The part of a convex ``polygon`` with ``normal . p <= limit`` (Sutherland-Hodgman, one half-plane)."""
    kept = []
    for i in range(len(polygon)):
        p, q = polygon[i], polygon[(i + 1) % len(polygon)]
        fp, fq = float(normal @ p) - limit, float(normal @ q) - limit
        if fp <= 0.0:
            kept.append(p)
        if fp * fq < 0.0:
            kept.append(p + (q - p) * fp / (fp - fq))
    return np.array(kept).reshape(-1, 2)


def target_view(target: Target, box: tuple[float, float, float, float]) -> TargetView:
    """The target's layers and faces inside ``box`` = ``(x_lo, x_hi, z_lo, z_hi)`` (m), world ``X`` and ``Z``: a
    point ``p`` lies ``-(n . p)`` deep, ``n = (sin i, cos i)`` the front face's normal turned by the inclination
    ``i``; gaps and the space behind the rear face are left empty."""
    x_lo, x_hi, z_lo, z_hi = box
    rectangle = np.array([[x_lo, z_lo], [x_hi, z_lo], [x_hi, z_hi], [x_lo, z_hi]], dtype=float)
    angle = math.radians(target.inclination)
    normal, along = np.array([math.sin(angle), math.cos(angle)]), np.array([math.cos(angle), -math.sin(angle)])
    layers = target.layers or []
    # each layer's top and bottom: the front face, the inner faces, and the rear face or none
    depths = [0.0, *target.inner_faces] + ([math.inf] if math.isinf(target.thickness) else [])
    materials = [layer.law != "air" for layer in layers] if layers else [True]
    bands: list[np.ndarray] = []
    shades: list[tuple[float, float, float]] = []
    laws = [repr(layer.law) for layer in layers] or [repr(target.law)]
    distinct = list(dict.fromkeys(law for law, material in zip(laws, materials) if material))
    for i, material in enumerate(materials):
        if not material:
            continue
        band = _clip(rectangle, normal, -depths[i])  # at least depths[i] deep
        if math.isfinite(depths[i + 1]):
            band = _clip(band, -normal, depths[i + 1])  # at most depths[i + 1] deep
        if len(band) >= 3:
            bands.append(band)
            shades.append(LAYER_SHADES[distinct.index(laws[i]) % len(LAYER_SHADES)])  # one shade per law
    reach = math.hypot(x_hi - x_lo, z_hi - z_lo) + abs(x_lo) + abs(x_hi) + abs(z_lo) + abs(z_hi)
    faces = [np.array([-d * normal - reach * along, -d * normal + reach * along]) for d in depths if math.isfinite(d)]
    return TargetView(bands, shades, faces)


def add_target(
    plotter: Plotter,
    pv: ModuleType,
    target: Target,
    box: tuple[float, float, float, float],
    y: float,
    lift: float,
    shades: Sequence[tuple[float, float, float]] = LAYER_SHADES,
) -> None:
    """Draw :func:`target_view` into a pyvista ``plotter`` seen along ``+Y``: the layers as flat polygons in the
    plane ``Y = y`` behind the body, in ``shades`` one after the other, the faces as brown lines ``lift`` (m) in
    front of them."""
    view = target_view(target, box)
    for i, band in enumerate(view.bands):
        points = np.column_stack([band[:, 0], np.full(len(band), y), band[:, 1]])
        polygon = pv.PolyData(points, np.concatenate([[len(band)], np.arange(len(band))]))
        plotter.add_mesh(polygon, color=shades[i % len(shades)], lighting=False)
    for face in view.faces:
        plotter.add_mesh(
            pv.Line((face[0, 0], y - lift, face[0, 1]), (face[1, 0], y - lift, face[1, 1])),
            color="saddlebrown",
            line_width=3,
            lighting=False,
        )
