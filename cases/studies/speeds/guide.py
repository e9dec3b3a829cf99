"""Guides of the characteristic-speed searches: where the reduced pitch-plane model applies, it says where
to look, and full runs decide.

The reduced model (:mod:`..reduced.pitch_plane`, docs/theory.md) finds both characteristic speeds of a body of
revolution in a homogeneous target within about one percent of the full simulator, in milliseconds.
A guide turns its answer into the first full runs of a search:

* **critical impact velocity**: the reduced model's change from stable to unstable, bisected to an
  eighth of the resolution, becomes a first bracket one resolution wide on the search's grid (half
  the resolution).  Full runs at both ends confirm it; an end its run contradicts gallops away from
  it, one resolution and then doubling (:func:`~cases.studies.speeds.characteristic.find_critical_velocities`).
* **characteristic convergent velocity**: the first of the raised impact speeds (the scene's, times
  1.15, 1.15^2, ...) whose reduced run is unstable; full runs at it and at the speed below it decide,
  and the measurement goes down, or on up, from there when they do not agree.

Where the reduced model does not apply (a projectile from a file, layers, a strength table, the
free-surface reduction, no separation, yaw or roll, :func:`..reduced.pitch_plane.check_supported`) the search runs
as it did unguided, and its result says why.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

from ...scene import InputError, Scene, one_line
from .instability import UNSTABLE_TURN, raised_speeds

if TYPE_CHECKING:
    from ..reduced.pitch_plane import ReducedModel

__all__ = ["GUIDES", "Guide", "critical_guide", "convergent_guide", "grid_bracket"]

GUIDES = ("auto", "reduced", "none")  # auto: reduced where it applies; reduced: refuse where it does not
FINER = 8  # the reduced bisection ends at resolution / FINER: its middle places the first bracket
GUIDE_RTOL = 1e-6  # the reduced runs' tolerance: at 1e-4 the predicted critical speed moves by up to 0.2 %


@dataclass(frozen=True)
class Guide:
    """What guides one search.

    ``name``: ``reduced`` or ``none``; ``text``: what the result says about it; ``predicted``: the
    reduced model's speed (m/s; for the convergent search, the first raised speed it finds unstable).
    """

    name: str
    text: str
    predicted: float | None = None

    @property
    def guided(self) -> bool:
        return self.name == "reduced"


def _unguided(guide: str, why: str) -> Guide:
    if guide == "reduced":
        raise InputError(f"--guide reduced: the reduced model does not apply here ({why}); use --guide auto or none")
    return Guide("none", f"unguided: the reduced model does not apply ({why})")


def _model(scene: Scene, guide: str) -> tuple[ReducedModel | None, Guide | None]:
    """The scene's reduced model, or the unguided guide that says why there is none."""
    if guide not in GUIDES:
        raise InputError(f"--guide {guide!r}: expected one of {', '.join(GUIDES)}")
    if guide == "none":
        return None, Guide("none", "unguided (--guide none)")
    from ...run import prepare_projectile
    from ..reduced.pitch_plane import ReducedModel, check_supported

    try:
        check_supported(scene)
    except InputError as exc:
        return None, _unguided(guide, one_line(exc))
    return ReducedModel(scene, prepare_projectile(scene), GUIDE_RTOL), None


def grid_bracket(centre: float, limits: tuple[float, float], resolution: float) -> tuple[float, float]:
    """A bracket one ``resolution`` wide around ``centre`` with its ends on the search's grid (multiples of
    half the resolution), inside ``limits``."""
    bottom, top = limits
    step = 0.5 * resolution
    low = round(round((centre - 0.5 * resolution) / step) * step, 6)
    low = min(max(low, bottom), top - resolution) if top - bottom > resolution else bottom
    return low, min(low + resolution, top)


def critical_guide(
    scene: Scene, limits: tuple[float, float], resolution: float, guide: str = "auto"
) -> tuple[Guide, tuple[float, float] | None]:
    """The guide of a critical-speed search in ``limits`` (m/s) and its first bracket (None: unguided).

    A reduced model stable up to the range's top (unstable down to its bottom) puts the bracket at that
    end: two full runs there confirm what it says, or the bracket moves out from it.
    """
    model, unguided = _model(scene, guide)
    if model is None:
        assert unguided is not None
        return unguided, None
    from ..reduced.pitch_plane import reduced_critical

    predicted, stable = reduced_critical(model, limits, resolution / FINER)
    if predicted is None:
        end, text = (limits[1], "stable up to") if stable else (limits[0], "unstable down to")
        return Guide("reduced", f"reduced model: {text} {end:g} m/s"), grid_bracket(end, limits, resolution)
    return Guide("reduced", f"reduced model: critical {predicted:.1f} m/s", predicted), grid_bracket(
        predicted, limits, resolution
    )


def convergent_guide(
    scene: Scene, raise_factor: float, max_speed: float, guide: str = "auto"
) -> tuple[Guide, int | None]:
    """The guide of a convergent-velocity measurement: how many times the scene's speed is raised by
    ``raise_factor`` before the reduced run turns unstable (None: unguided, or no unstable reduced run
    up to ``max_speed``)."""
    model, unguided = _model(scene, guide)
    if model is None:
        assert unguided is not None
        return unguided, None
    for raised, speed in enumerate(raised_speeds(scene.impact.speed, raise_factor, max_speed)):
        if model.run(round(speed, 6), turn_limit=UNSTABLE_TURN).unstable:
            text = f"reduced model: first unstable at {speed:.6g} m/s" + (f" (raised {raised} times)" if raised else "")
            return Guide("reduced", text, round(speed, 6)), raised
    return Guide("reduced", f"reduced model: stable up to {max_speed:g} m/s"), None
